"""Plane (2D) continua: meshes, elements, assembly, the compiled system, closed forms and crack integrals."""
