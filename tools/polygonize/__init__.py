"""polygonize: Polygonize a .floret frame sequence (thesis 2.4) into OBJ frames of identical topology."""
