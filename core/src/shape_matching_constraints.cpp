// (being written: the shape_matching batch kernel)
