"""The seed's low-order dynamical system (issue 28 item 5; seed 002, Khayat & Ashrafi, section 2): js_galerkin.

References: the Galerkin projection of the channel PDEs (Re u_t = We + S_y + epsilon u_yy, N_t = -N + 2 S u_y,
S_t = -S + u_y (1 + a N)) on the modes u = A phi, S = B phi', N = C phi'^2, phi = 1 - 4 y^2, redone here with
sympy's exact integrals over [-1/2, 1/2] and compared with the model's rates symbolically; the steady branch
solved in closed form with sympy (We as a function of A) and its folds as the exact roots of dWe/dA = 0; the
continuation scene's folds and its stability verdict against those; the Jacobian of the generated kernel against
sympy's Jacobian of the projected system.
"""
from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import sympy as sp

import mechgen
from mechgen.models import js_galerkin as jg
from mechgen.scene.run import run_scene

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "js_galerkin.toml"
y, A, B, C = sp.symbols("y A B C", real=True)
eps, xi, Re, We = sp.symbols("epsilon xi Re We", positive=True)
PHI = 1 - 4 * y**2


def projected_rates():
    """(A', B', C') from projecting each PDE on its own mode, the integrals done exactly by sympy."""
    u, S, N = A * PHI, B * sp.diff(PHI, y), C * sp.diff(PHI, y) ** 2
    u_y = sp.diff(u, y)
    a = xi * (xi / 2 - 1)
    rhs = {  # field equations' right-hand sides, divided by the time-derivative coefficient (Re for u)
        "A": ((We + sp.diff(S, y) + eps * sp.diff(u, y, 2)) / Re, PHI),
        "B": (-S + u_y * (1 + a * N), sp.diff(PHI, y)),
        "C": (-N + 2 * S * u_y, sp.diff(PHI, y) ** 2),
    }
    half = sp.Rational(1, 2)
    return {k: sp.integrate(r * m, (y, -half, half)) / sp.integrate(m**2, (y, -half, half))
            for k, (r, m) in rhs.items()}


def model_rates():
    z = SimpleNamespace(u1=A, txy1=B, N1=C)
    p = SimpleNamespace(epsilon=eps, xi=xi, Re=Re, We=We)
    coupling = sp.Rational(48, 5)  # the model's float 48/5 as the exact rational it stands for
    b = jg.shear_rate_of_change(z, p).subs(jg.NU_COUPLING, coupling)
    return {"A": jg.velocity_rate(z, p), "B": sp.nsimplify(b), "C": -C + 2 * A * B}


def test_projection_matches_model():
    proj, mod = projected_rates(), model_rates()
    for k in "ABC":
        assert sp.simplify(proj[k] - mod[k]) == 0, k
    assert jg.NU_COUPLING == 48 / 5


def steady_we(a_val, epsilon, x):
    """The closed-form steady branch We(A) = 8 epsilon A + 8 A / (1 + (48/5) xi (2 - xi) A^2)."""
    return 8 * epsilon * a_val + 8 * a_val / (1 + sp.Rational(48, 5) * x * (2 - x) * a_val**2)


def test_steady_branch_closed_form():
    """sympy's solution of the projected steady equations is the branch We(A) above, B and C with it."""
    proj = projected_rates()
    sol = sp.solve([proj["A"], proj["B"], proj["C"]], [We, B, C], dict=True)
    assert len(sol) == 1
    assert sp.simplify(sol[0][We] - steady_we(A, eps, xi)) == 0
    assert sp.simplify(sol[0][C] - 2 * A * sol[0][B]) == 0


def fold_points(epsilon, x):
    """Exact roots A > 0 of dWe/dA = 0 (sympy, rational parameters) and We there: the two folds."""
    e, xr = sp.nsimplify(epsilon), sp.nsimplify(x)
    roots = sp.solve(sp.diff(steady_we(A, e, xr), A), A)
    pos = sorted(float(r) for r in roots if r.is_real and r > 0)
    return [(a_val, float(steady_we(sp.nsimplify(a_val), e, xr).evalf(30))) for a_val in pos] if pos else []


def test_folds_are_the_shear_curve_extrema_rescaled():
    """We_fold = (8 / c) T_extremum with c = sqrt(48/5): the folds are the shear curve's extrema."""
    from mechgen.runtime.fluids import johnson_segalman as js
    (g_max, t_max), (g_min, t_min) = js.extrema(0.08, 0.2)
    c = np.sqrt(48 / 5)
    (a1, we1), (a2, we2) = fold_points(0.08, 0.2)
    assert abs(we1 - 8 / c * t_max) < 1e-12 and abs(we2 - 8 / c * t_min) < 1e-12  # round-off of sqrt and ratios
    assert abs(a1 * c - g_max) < 1e-12 and abs(a2 * c - g_min) < 1e-12
    assert fold_points(0.2, 0.2) == []  # epsilon >= 1/8: monotone branch, no fold (as the seed's 1/8 threshold)


@pytest.fixture(scope="module")
def scene():
    return {a["name"]: a["outputs"] for a in run_scene(str(SCENE))["analyses"]}


def test_scene_folds_and_stability(scene):
    (a1, we1), (a2, we2) = fold_points(0.08, 0.2)
    points = scene["branch"]["special_points"]
    assert [p["type"] for p in points] == ["LP", "LP"]  # no Hopf point at Re = 1 (trace < 0, see below)
    # folds located by bisection of the fold test function to the continuation's 1e-10 relative tolerance
    assert abs(points[0]["We"] - we1) < 1e-8 and abs(points[1]["We"] - we2) < 1e-8
    assert abs(points[0]["wall_shear_rate"] - 4 * a1) < 1e-5 and abs(points[1]["wall_shear_rate"] - 4 * a2) < 1e-5
    changes = [(c["from"], c["to"]) for c in scene["branch"]["stability_changes"]]
    assert changes == [("stable", "divergence"), ("divergence", "stable")]  # the middle branch: a saddle


def test_scene_stability_at_we_2(scene):
    """At We = 2 (below both folds: one steady state) the eigenvalues equal those of sympy's Jacobian at the
    closed-form state, A the real root of We(A) = 2."""
    e, x = sp.Rational(8, 100), sp.Rational(1, 5)
    roots = [r for r in sp.Poly(sp.numer(sp.together(steady_we(A, e, x) - 2)), A).nroots(n=30) if r.is_real]
    assert len(roots) == 1
    av = roots[0]
    b_val = av / (1 + sp.Rational(48, 5) * x * (2 - x) * av**2)
    proj = projected_rates()
    jac = sp.Matrix([proj[k] for k in "ABC"]).jacobian([A, B, C])
    exact = np.array(jac.subs({eps: e, xi: x, Re: 1, We: 2, A: av, B: b_val, C: 2 * av * b_val}).evalf(30),
                     dtype=float)
    lam = np.sort_complex(np.linalg.eigvals(exact))
    got = np.sort_complex(np.array([complex(*s) for s in scene["lower"]["eigenvalues"]]))
    assert scene["lower"]["verdict"] == "stable"
    assert np.allclose(got, lam, rtol=0, atol=1e-10)  # Newton's state to its 1e-10 residual tolerance
    assert abs(scene["lower_state"]["wall_shear_rate"] - 4 * float(av)) < 1e-10


def test_generated_jacobian_matches_sympy():
    """The generated kernel's Jacobian equals sympy's Jacobian of the projected system on all three branches;
    the middle branch has exactly one positive real eigenvalue, the outer ones none."""
    proj = projected_rates()
    jac = sp.Matrix([proj[k] for k in "ABC"]).jacobian([A, B, C])
    values = {eps: sp.Rational(8, 100), xi: sp.Rational(1, 5), Re: 1}
    system = mechgen.compile("js_galerkin", params={"epsilon": 0.08, "xi": 0.2, "Re": 1.0}, free=["We"])
    (a1, _), (a2, _) = fold_points(0.08, 0.2)
    for a_val, positive in ((0.3, 0), ((a1 + a2) / 2, 1), (3.0, 0)):
        av = sp.nsimplify(a_val)
        b_val = av / (1 + sp.Rational(48, 5) * sp.Rational(9, 25) * av**2)
        state = {A: av, B: b_val, C: 2 * av * b_val}
        we = steady_we(av, sp.Rational(8, 100), sp.Rational(1, 5))
        exact = np.array(jac.subs({**values, **state, We: we}).evalf(20), dtype=float)
        num = system.with_params(We=float(we)).jacobian(0.0, np.array([float(state[s]) for s in (A, B, C)]))
        assert np.allclose(num, exact, rtol=0, atol=1e-12)
        lam = np.linalg.eigvals(exact)
        assert sum(1 for s in lam if s.real > 0) == positive and lam.real.sum() < 0


def test_no_hopf_point_anywhere_on_the_branch():
    """Routh-Hurwitz on the steady branch: with l^3 + a1 l^2 + a2 l + a3 the characteristic polynomial of the
    projected Jacobian, a Hopf point needs a1 a2 = a3 (and a2 > 0). sympy gives a1 a2 - a3 as a ratio of
    polynomials in A, Re, epsilon, k = xi (2 - xi) with positive coefficients only: it never vanishes, for every
    epsilon, xi, Re > 0 (the scene's branch reports no H point)."""
    k, lam = sp.symbols("k lambda", positive=True)
    proj = projected_rates()
    jac = sp.Matrix([proj[s] for s in "ABC"]).jacobian([A, B, C])
    b_val = A / (1 + sp.Rational(48, 5) * k * A**2)
    jac = jac.subs({C: 2 * A * B}).subs({B: b_val}).subs({xi: 1 - sp.sqrt(1 - k)})  # xi (2 - xi) = k
    _, a1, a2, a3 = jac.charpoly(lam).all_coeffs()
    num, den = sp.fraction(sp.factor(sp.together(sp.expand(a1 * a2 - a3))))
    for part in (num, den):
        coeffs = sp.Poly(sp.expand(part), A, Re, eps, k).coeffs()
        assert coeffs and all(cf > 0 for cf in coeffs)
