"""Closed forms of non-Newtonian fluid laws in simple flows (``johnson_segalman``). Numerics only."""
