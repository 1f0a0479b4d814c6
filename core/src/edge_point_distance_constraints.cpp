// (being written: the edge_point_distance batch kernel)
