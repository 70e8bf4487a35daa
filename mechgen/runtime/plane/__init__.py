"""Plane (2D) continua, numerics only: meshes (:mod:`.mesh`), Lagrange elements, quadrature, the isoparametric
map and jet tables (:mod:`.elements`), factored assembly (:mod:`.assemble`), edges (:mod:`.edges`), points
(:mod:`.points`), the discretisation and the compiled system (:mod:`.discretise`, :mod:`.system`), closed forms
and crack integrals."""
