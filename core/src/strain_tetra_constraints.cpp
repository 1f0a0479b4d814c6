// (being written: the strain_tetra batch kernel)
