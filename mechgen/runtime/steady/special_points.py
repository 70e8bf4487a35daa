"""Special points of an equilibrium branch F(y, p) = 0: folds (LP), branch points (BP) and Hopf points (H).

Along a branch x(s) = (y(s), p(s)) of F: R^{n+1} -> R^n (mechgen.runtime.steady.continuation), each kind of
point is the zero of a test function that changes sign there, bracketed between two accepted points and located
by bisection along the branch (:func:`bisect`: points corrected onto the branch, to 1e-10 of the segment, or as
near as the corrector still converges):

* **LP** (fold, limit point): the tangent's p-component t_p changes sign (located by the continuation itself).
* **BP** (simple branch point): psi_BP = det [[F_y, F_p], [c^T]], c the segment's chord. [F_y F_p] has a
  two-dimensional null space at a BP, and this determinant changes sign where a branch crosses another one —
  and not at a fold, where [F_y F_p] keeps full rank. It counts no eigenvalues, so a pitchfork is found on
  either branch through it, also where no eigenvalue of F_y changes sign along the branch that arrives
  (BifurcationKit #223).
* **H** (Hopf): the bialternate product psi_H = prod_{i<j} (lambda_i + lambda_j) over the eigenvalues of the
  first-order Jacobian A = d(dx/dt)/dx at the equilibrium changes sign where a complex pair crosses the
  imaginary axis; it also vanishes at a neutral saddle (two real eigenvalues +-mu), which the located point's
  spectrum tells apart (a pair +-i omega with omega > 0 is a Hopf point; no such pair: not reported).

At a Hopf point the **first Lyapunov coefficient** (Kuznetsov, Elements of Applied Bifurcation Theory, 3rd ed.,
eq. 3.20, with A q = i omega q, A^T p = -i omega p, <p, q> = conj(p)^T q = 1, <q, q> = 1)

    l1 = 1/(2 omega) Re[ <p, C(q, q, conj q)> - 2 <p, B(q, A^-1 B(q, conj q))>
                         + <p, B(conj q, (2 i omega I - A)^-1 B(q, q))> ]

says whether the bifurcation is supercritical (l1 < 0: a stable cycle is born) or subcritical (l1 > 0); its
magnitude depends on the eigenvector's normalisation, its sign does not. Below :func:`lyapunov_resolution` it is
zero to working precision (a linear model's Hopf point is degenerate: no cycle is born). B and C,
the second and third derivatives of the vector field f(x) (dx/dt = f), are directional derivatives of the exact
(generated) Jacobian J(x) by central differences: B(u, w) = [J(x + h u) - J(x - h u)] w / (2h),
C(u, u', w) = [J(x + h u + h u') - J(x + h u - h u') - J(x - h u + h u') + J(x - h u - h u')] w / (4 h^2), with
h = LYAPUNOV_STEP for the unit eigenvector (exact for a polynomial field up to quartic terms; otherwise an
O(h^2) error). Complex arguments are expanded by multilinearity into real ones.

Branch switching at a BP: the null space of [F_y F_p] there (the two right singular vectors of least singular
value) holds the known branch's tangent t and the other branch's direction d, the part of the null space
orthogonal to t; :func:`other_direction` returns it, and the continuation starts along +-d from the BP.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.steady import branch_scan

#: the difference step of the Lyapunov coefficient's B and C, for a unit eigenvector (module doc)
LYAPUNOV_STEP = 1e-3
#: a located zero of psi_H is a Hopf point when its critical pair has |Im| above this share of the spectrum's
#: largest magnitude (below it: a neutral saddle, or a double zero eigenvalue, not reported as H)
HOPF_IMAG_SHARE = 1e-7
#: bisection tolerance along a segment (its share of the chord; :func:`bisect`)
LOCATE_TOL = 1e-10
#: the most bisection steps of a location: 2^-60 of the chord is far below LOCATE_TOL (34 steps reach it when the
#: corrected points stay on the bracket's piece of branch)
BISECT_STEPS = 60


@dataclass(frozen=True)
class SpecialPoint:
    """A located special point: its ``type`` (LP, BP or H), x = (y, p), the segment ``index`` it lies on (between
    branch points index and index + 1) and what the type adds (``data``: for H omega and l1, for BP the other
    branch's direction)."""

    type: str
    x: np.ndarray
    index: int
    data: dict = field(default_factory=dict)


def dense(matrix) -> np.ndarray:
    """A matrix as a dense float array (a sparse one converted)."""
    return np.asarray(matrix.toarray() if hasattr(matrix, "toarray") else matrix, float)


def augmented(eqs, x: np.ndarray) -> np.ndarray:
    """[F_y, F_p] at x = (y, p), dense (n, n + 1)."""
    y, p = x[:-1], float(x[-1])
    return np.hstack([dense(eqs.F_u(y, p)), np.asarray(eqs.F_lam(y, p), float).reshape(-1, 1)])


def bp_sign(eqs, x: np.ndarray, row: np.ndarray) -> int:
    """sign det [[F_y, F_p], [row^T]] at x (0 when singular to working precision)."""
    sign, _ = np.linalg.slogdet(np.vstack([augmented(eqs, x), row.reshape(1, -1)]))
    return int(np.sign(sign))


def hopf_sign(eigenvalues: np.ndarray) -> int:
    """sign prod_{i<j} (lambda_i + lambda_j) (the product is real: its factors come in conjugate pairs)."""
    lam = np.asarray(eigenvalues, complex).ravel()
    i, j = np.triu_indices(lam.size, 1)
    sums = lam[i] + lam[j]
    if np.any(sums == 0):
        return 0
    phase = np.prod(sums / np.abs(sums))
    return int(np.sign(phase.real))


def critical_pair(eigenvalues: np.ndarray) -> complex:
    """The eigenvalue with Im >= 0 nearest the imaginary axis."""
    lam = np.asarray(eigenvalues, complex).ravel()
    upper = lam[lam.imag >= 0]
    return complex(upper[np.argmin(np.abs(upper.real))])


def is_hopf(eigenvalues: np.ndarray) -> bool:
    """Whether the critical eigenvalue is a pair +-i omega with omega > 0 (not a neutral saddle)."""
    lam = np.asarray(eigenvalues, complex).ravel()
    scale = max(float(np.max(np.abs(lam), initial=0.0)), 1e-300)
    return critical_pair(lam).imag > HOPF_IMAG_SHARE * scale


def first_lyapunov(jacobian: Callable[[np.ndarray], np.ndarray], x0: np.ndarray, step: float = LYAPUNOV_STEP) -> tuple[float, float]:
    """(omega, l1) at a Hopf equilibrium x0 of dx/dt = f(x), J = ``jacobian(x)`` (module doc)."""
    import scipy.linalg as sla

    A = np.asarray(jacobian(x0), float)
    lam, vl, vr = sla.eig(A, left=True, right=True)
    k = int(np.argmin(np.where(lam.imag > 0, np.abs(lam.real), np.inf)))
    omega = float(lam[k].imag)
    q = vr[:, k] / np.linalg.norm(vr[:, k])
    p = vl[:, k] / np.conj(np.vdot(vl[:, k], q))      # A^T p = -i omega p, conj(p)^T q = 1
    B, C = multilinear(jacobian, x0, step)
    n = A.shape[0]
    h11 = np.linalg.solve(A, B(q, np.conj(q)))
    h20 = np.linalg.solve(2j * omega * np.eye(n) - A, B(q, q))
    value = np.vdot(p, C(q, q, np.conj(q))) - 2 * np.vdot(p, B(q, h11)) + np.vdot(p, B(np.conj(q), h20))
    return omega, float(value.real / (2 * omega))


def lyapunov_resolution(A: np.ndarray, omega: float, step: float = LYAPUNOV_STEP) -> float:
    """The least |l1| the differences resolve: 100 eps ||A||_F / (h^2 omega), the round-off of C's second
    difference of J for a unit eigenvector. Below it l1 is zero to working precision (a linear field, or a
    degenerate Hopf point) and no criticality is claimed."""
    return 100 * np.finfo(float).eps * float(np.linalg.norm(A)) / (step * step * omega)


def multilinear(jacobian: Callable, x0: np.ndarray, h: float) -> tuple[Callable, Callable]:
    """(B, C): complex bilinear and trilinear forms of f's 2nd and 3rd derivatives at x0 from J (module doc)."""
    def d1(u):  # D_u J, u real
        return (jacobian(x0 + h * u) - jacobian(x0 - h * u)) / (2 * h)

    def d2(u, w):  # D_u D_w J, u, w real
        return (jacobian(x0 + h * (u + w)) - jacobian(x0 + h * (u - w)) - jacobian(x0 - h * (u - w))
                + jacobian(x0 - h * (u + w))) / (4 * h * h)

    def B(u, w):
        ur, ui = u.real, u.imag
        out = d1(ur) @ w
        return out + 1j * (d1(ui) @ w) if np.any(ui) else out

    def C(u, v, w):
        parts = [(u.real, 1.0), (u.imag, 1j)]
        total = np.zeros(x0.size, complex)
        for a, ca in parts:
            for b, cb in ((v.real, 1.0), (v.imag, 1j)):
                if np.any(a) and np.any(b):
                    total += ca * cb * (d2(a, b) @ w)
        return total

    return B, C


def other_direction(eqs, x: np.ndarray, known: np.ndarray) -> np.ndarray:
    """The unit direction of the other branch through a BP at x: the part of the null space of [F_y F_p] (its two
    right singular vectors of least singular value) orthogonal to the known branch's direction ``known``."""
    _, _, vt = np.linalg.svd(augmented(eqs, x))
    null = vt[-2:]
    t = null.T @ (null @ known)
    t = t / np.linalg.norm(t)
    d = null.T @ (null @ np.random.default_rng(1).standard_normal(x.size))
    d = d - (d @ t) * t
    return d / np.linalg.norm(d)


def bisect(eqs, xa: np.ndarray, xb: np.ndarray, value: Callable) -> np.ndarray:
    """The zero of the test function ``value`` between the branch points xa and xb (opposite signs): bisection
    along the segment (points corrected onto the branch, mechgen.runtime.steady.branch_scan.point_between) to
    LOCATE_TOL of it (at most BISECT_STEPS halvings), or until a point cannot be corrected (near a BP the bordered
    system is singular), then one secant step between the last two corrected points, x = x_a + (x_b - x_a) v_a / (v_a - v_b): off the branch
    by the square of the last bracket (the branch's curvature times it)."""
    x_lo, x_hi = np.asarray(xa, float), np.asarray(xb, float)
    v_lo, v_hi = value(x_lo), value(x_hi)
    width = float(np.linalg.norm(x_hi - x_lo))
    for _ in range(BISECT_STEPS):  # the chord halves each step; the corrected points may not follow it (a sheet
        if np.linalg.norm(x_hi - x_lo) <= LOCATE_TOL * width:  # jumped near a fold cascade): bounded, never a hang
            break
        try:  # the middle of the current bracket: its chord's error shrinks with the square of its length
            x = branch_scan.point_between(eqs, x_lo, x_hi, 0.5)
        except ConvergenceError:
            break
        v = value(x)
        if v == 0:
            return x
        if np.sign(v) == np.sign(v_lo):
            x_lo, v_lo = x, v
        else:
            x_hi, v_hi = x, v
    return x_lo + (x_hi - x_lo) * (v_lo / (v_lo - v_hi))


def bp_value(eqs, row: np.ndarray, reference: np.ndarray) -> Callable:
    """x -> det [[F_y, F_p], [row^T]] at x over |det| at ``reference`` (scaled: no overflow)."""
    def det(x):
        return np.linalg.slogdet(np.vstack([augmented(eqs, x), row.reshape(1, -1)]))

    _, ref = det(reference)

    def value(x):
        sign, logdet = det(x)  # one factorisation per evaluation
        return float(sign * np.exp(logdet - ref))

    return value


def branch_points(eqs, X: np.ndarray) -> list[SpecialPoint]:
    """The BPs between consecutive rows of X (branch points (y, p)): sign changes of psi_BP with each segment's
    chord as the border row, located by bisection; each with the other branch's direction."""
    found = []
    for i in range(len(X) - 1):
        chord = X[i + 1] - X[i]
        if not np.any(chord):
            continue
        row = chord / np.linalg.norm(chord)
        a, b = bp_sign(eqs, X[i], row), bp_sign(eqs, X[i + 1], row)
        if a * b >= 0:
            continue
        x = bisect(eqs, X[i], X[i + 1], bp_value(eqs, row, X[i]))
        found.append(SpecialPoint("BP", x, i, {"direction": other_direction(eqs, x, row)}))
    return found


def polish_hopf(eqs, x: np.ndarray, chord: np.ndarray, eigenvalues: Callable) -> np.ndarray:
    """x refined by the secant on Re of the critical pair between two corrected points 1e-6 of the chord either
    side of x (the pair that crosses is the one nearest the axis there); x unchanged when they do not bracket."""
    h = 1e-6 * chord
    try:
        a = branch_scan.point_between(eqs, x - h, x + h, 0.0)
        b = branch_scan.point_between(eqs, x - h, x + h, 1.0)
    except ConvergenceError:
        return x
    va, vb = critical_pair(eigenvalues(a)).real, critical_pair(eigenvalues(b)).real
    if va * vb > 0 or va == vb:
        return x
    return a + (b - a) * (va / (va - vb))


def hopf_points(eqs, X: np.ndarray, eigenvalues: Callable[[np.ndarray], np.ndarray],
                jacobian_at: Callable[[np.ndarray], Callable]) -> list[SpecialPoint]:
    """The Hopf points between consecutive rows of X: sign changes of psi_H (``eigenvalues(x)``: the first-order
    spectrum at the branch point x), located by bisection, kept when the critical pair is +-i omega; each with
    omega and l1 (``jacobian_at(x)``: (J of the first-order field at the parameter of x, the equilibrium state))."""
    signs = [hopf_sign(eigenvalues(x)) for x in X]
    found = []
    for i in range(len(X) - 1):
        if signs[i] * signs[i + 1] >= 0:
            continue
        x = bisect(eqs, X[i], X[i + 1], lambda z: hopf_sign(eigenvalues(z)))
        x = polish_hopf(eqs, x, X[i + 1] - X[i], eigenvalues)
        if not is_hopf(eigenvalues(x)):
            continue
        jac, state = jacobian_at(x)
        omega, l1 = first_lyapunov(jac, state)
        found.append(SpecialPoint("H", x, i, {"frequency": omega, "lyapunov": l1,
                                              "resolution": lyapunov_resolution(jac(state), omega)}))
    return found
