// (being written: the strain_triangle batch kernel)
