// (being written: the triangle_point_distance batch kernel)
