// (being written: the edge_edge_distance batch kernel)
