// (being written: the volume batch kernel)
