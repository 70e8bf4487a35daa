"""Steady states, boundary-value problems and continuation: Newton's method (``newton``), BVPs by
shooting (``bvp``) and collocation (``collocation``), pseudo-arclength continuation
(``continuation``), branch scans and switching (``branch_scan``) and the stability along a branch
(``branch_stability``), steady BVPs of a field model (``steady_bvp``, ``steady_kernels``), the
linearisation of a constrained steady state (``constrained``) and starting guesses (``guesses``)."""
