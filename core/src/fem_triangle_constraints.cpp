// (being written: the fem_triangle batch kernel)
