// (being written: the isometric_bending batch kernel)
