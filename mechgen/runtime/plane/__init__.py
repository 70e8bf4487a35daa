"""Plane (2D) continua, numerics only: meshes (:mod:`.mesh`), Lagrange elements, quadrature, the isoparametric
map, jet and edge tables (:mod:`.elements`), points in a mesh (:mod:`.locate`). Assembly reuses
:mod:`mechgen.runtime.fields.assemble`."""
