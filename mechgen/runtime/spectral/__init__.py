"""Spectral collocation on [-1, 1]: Chebyshev points and differentiation matrices (``chebyshev``), the
two-resolution filter of computed eigenvalues (``chebyshev.resolved``) and the linear stability of parallel
shear flows built on them (``orr_sommerfeld``). Numerics only: no sympy, no kernels."""
