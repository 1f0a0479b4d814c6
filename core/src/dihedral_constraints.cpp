// (being written: the dihedral batch kernel)
