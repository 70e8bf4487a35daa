"""Names of the discretisations a continuum scene may choose (implemented in mechgen.runtime.fields.discretise).

Finite elements (N = elements): ``lagrange1`` and ``lagrange2`` (C0, jets up to
first order in the energy), ``hermite`` (two-node cubic, value and slope per
node, C1) and ``quintic`` (three-node quintic Hermite, value and slope at three
nodes, C1), ``timoshenko2`` (the two-node shaft element of rotordynamics: each
declared shear pair (w, psi) interpolated together by the exact static solution,
cubic w and quadratic psi). Global Galerkin bases (N = functions per field): ``sine``
sin(j pi s/L), j = 1..N; ``cosine`` cos(j pi s/L), j = 0..N-1; ``legendre``
P_j(2 s/L - 1), j = 0..N-1; ``beam``, Euler-Bernoulli beam eigenfunctions of the
field's end conditions.
"""
DISCRETISATIONS = ("hermite", "quintic", "lagrange1", "lagrange2", "timoshenko2", "sine", "cosine", "legendre", "beam")
