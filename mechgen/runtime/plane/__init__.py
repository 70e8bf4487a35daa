"""Plane (2D) continua, numerics only: meshes (:mod:`.mesh`), Lagrange elements, quadrature, the isoparametric
map and jet tables (:mod:`.elements`). Assembly reuses :mod:`mechgen.runtime.fields.assemble`."""
