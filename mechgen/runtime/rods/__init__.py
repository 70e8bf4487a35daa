"""Rods on SE(3): Lie-group numerics (``liegroup``) and the solvers built on them."""
