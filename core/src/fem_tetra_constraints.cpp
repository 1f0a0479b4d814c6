// (being written: the fem_tetra batch kernel)
