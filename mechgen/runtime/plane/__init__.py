"""Plane (2D) continua: meshes, elements, closed-form reference fields and the fracture integrals."""
