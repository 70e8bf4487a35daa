"""Continuum discretisation and assembly: meshes and dof maps (``mesh``), polynomial bases
(``bases``), reference elements (``elements``), the Galerkin discretisations (``discretise``),
element assembly (``assemble``), constraints and their reductions (``constrain``) and the compiled
field system (``continuum``)."""
