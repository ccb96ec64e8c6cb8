"""Test meshes and functions: mesh primitives, Franke's test functions, OBJ reading/writing."""
