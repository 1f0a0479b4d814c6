// (being written: the particle_tet_contact batch kernel)
