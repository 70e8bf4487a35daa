"""Non-variational continua: Beck's follower-loaded column (a weak form at the tip) and Timoshenko beams.

Beck's column (Beck, Z. angew. Math. Phys. 3 (1952) 225; Bolotin, Nonconservative
Problems of the Theory of Elastic Stability, 1963): EI w'''' + P w'' + rhoA w_tt = 0,
w(0) = w'(0) = 0, w''(L) = w'''(L) = 0. With w ~ exp(i omega t), alpha^2, beta^2 =
(sqrt(P^2 + 4 EI rhoA omega^2) +- P) / (2 EI), the frequency equation (L = 1) is

    alpha^4 + beta^4 + 2 alpha^2 beta^2 cos(alpha) cosh(beta) + alpha beta (alpha^2 - beta^2) sin(alpha) sinh(beta) = 0,

whose two lowest roots merge at P_cr = 20.05 EI/L^2 (flutter). P_cr is recomputed here
from that equation, independently of mechgen.

Timoshenko beam, pinned-pinned: each k = n pi / L gives the two roots in omega^2 of
(kGA k^2 - rhoA omega^2)(EI k^2 + kGA - rhoI omega^2) = kGA^2 k^2 (e.g. Han, Benaroya &
Wei, J. Sound Vib. 225 (1999) 935, eq. 88).
"""
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.analyses.modes import run_modes
from mechgen.analyses.stability import run_stability
from mechgen.symbolic.specialize import specialize


def beck_roots(P: float, omega_max: float = 30.0) -> list[float]:
    """Roots omega of Beck's frequency equation below omega_max (EI = rhoA = L = 1)."""
    def f(w):
        root = np.sqrt(P**2 + 4 * w**2)
        a, b = np.sqrt((root + P) / 2), np.sqrt((root - P) / 2)
        return (a**4 + b**4 + 2 * a**2 * b**2 * np.cos(a) * np.cosh(b)
                + a * b * (a**2 - b**2) * np.sin(a) * np.sinh(b)) / np.cosh(b)
    grid = np.linspace(0.5, omega_max, 3000)
    vals = f(grid)
    return [brentq(f, x0, x1) for x0, x1, v0, v1 in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]) if v0 * v1 < 0]


def beck_critical_load() -> float:
    lo, hi = 15.0, 25.0
    while hi - lo > 1e-9:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if len(beck_roots(mid)) >= 2 else (lo, mid)
    return (lo + hi) / 2


def column(P, N=32, backend="c"):
    model = models.get("follower_column")
    system, _ = compile_model(model, specialize(model, {"P": P, "N": N}), kernels={"linear"}, backend=backend)
    return system


def test_beck_reference_is_the_published_value():
    assert beck_critical_load() == pytest.approx(20.05, abs=0.01)


def test_beck_frequencies_below_flutter():
    for P in (0.0, 10.0, 19.0):
        out = run_stability(column(P), {"count": 2, "refine": False}, {})
        assert out["verdict"] == "stable"
        assert np.allclose(out["frequencies"][:2], beck_roots(P)[:2], rtol=1e-5)


def test_beck_flutter_load():
    """Bisect the verdict of the discretised column (hermite, 32 elements): P_cr to 1e-5."""
    lo, hi = 15.0, 25.0
    while hi - lo > 1e-6:
        mid = (lo + hi) / 2
        verdict = run_stability(column(mid), {"refine": False}, {})["verdict"]
        assert verdict in ("stable", "flutter")
        lo, hi = (mid, hi) if verdict == "stable" else (lo, mid)
    assert (lo + hi) / 2 == pytest.approx(beck_critical_load(), rel=1e-5)


def test_beck_flutter_survives_refinement():
    out = run_stability(column(23.0, N=16), {}, {})
    assert out["verdict"] == "flutter"
    assert out["refinement"]["verdicts"] == ["flutter", "flutter"]


def test_beck_frequencies_sparse_at_a_thousand_elements():
    """N = 1000 (n = 2000 > SPARSE_STABILITY_N: ARPACK shift-invert): the three lowest frequencies against the
    frequency equation. The shift follows the lowest mode (runtime/linear/stability.low_shift); the former
    shift, -1e-6 sqrt(max K_ii / max M_ii), grew as N^2 (-5.7 here) and left 1.6e-6 relative error at the
    first frequency (and ARPACK crawling at N = 16 000). Tolerance 1e-6: 100 x ARPACK's relative tolerance
    (1e-8) for the amplification by the pencil's conditioning (measured 6e-8); the Hermite elements' own
    error, O(h^4) = 1e-12, is below it."""
    out = run_stability(column(10.0, N=1000), {"count": 3, "refine": False}, {})
    assert out["verdict"] == "stable"
    assert np.allclose(out["frequencies"][:3], beck_roots(10.0, 60.0)[:3], rtol=1e-6, atol=0)


@pytest.mark.parametrize("backend", ["numpy", "casadi"])
def test_point_terms_on_every_backend(backend):
    ref = run_stability(column(12.0, N=8), {"refine": False}, {})["frequencies"]
    other = run_stability(column(12.0, N=8, backend=backend), {"refine": False}, {})["frequencies"]
    assert np.allclose(other, ref, rtol=1e-12)


def timoshenko_exact(n_modes, EI=1.0, kGA=1e3, rhoA=1.0, rhoI=1e-3, L=1.0):
    k = np.arange(1, n_modes + 1) * np.pi / L
    a = rhoA * rhoI
    b = -(rhoA * (EI * k**2 + kGA) + rhoI * kGA * k**2)
    c = kGA * k**2 * (EI * k**2 + kGA) - kGA**2 * k**2
    disc = np.sqrt(b * b - 4 * a * c)
    return np.sqrt((-b - disc) / (2 * a)), np.sqrt((-b + disc) / (2 * a))


@pytest.mark.parametrize("disc,size,bound", [("quintic", 8, 2e-6), ("legendre", 20, 1e-9), ("hermite", 32, 5e-6)])
def test_timoshenko_pinned_both_spectra(disc, size, bound):
    model = models.get("timoshenko_beam")
    system, _ = compile_model(model, specialize(model, {"discretisation": disc, "N": size}), kernels={"linear"})
    freqs = np.array(run_modes(system, {}, {})["frequencies"])
    low, high = timoshenko_exact(6)
    assert np.abs(freqs[:6] / low - 1).max() < bound
    # the first mode of the second (shear) spectrum, where it falls in the computed spectrum
    nearest = freqs[np.argmin(np.abs(freqs - high[0]))]
    assert nearest == pytest.approx(high[0], rel=10 * bound)


def test_timoshenko_tends_to_euler_bernoulli():
    """Stiff shear, small rotary inertia: omega_T = omega_EB (1 - k^2 (EI/kGA + rhoI/rhoA) / 2 + O(k^4))."""
    model = models.get("timoshenko_beam")
    spec = specialize(model, {"discretisation": "legendre", "N": 20, "kGA": 1e6, "rhoI": 1e-6})
    system, _ = compile_model(model, spec, kernels={"linear"})
    freqs = np.array(run_modes(system, {"count": 4}, {})["frequencies"])
    k = np.arange(1, 5) * np.pi
    shift = 1 - freqs / k**2
    assert np.allclose(shift, k**2 * (1e-6 + 1e-6) / 2, rtol=0.05)


def test_linear_elements_lock_in_shear():
    """Hard case: equal-order linear elements lock for a slender beam (error far above quadratic ones)."""
    model = models.get("timoshenko_beam")
    low, _ = timoshenko_exact(1)
    errs = {}
    for disc in ("lagrange1", "lagrange2"):
        system, _ = compile_model(model, specialize(model, {"discretisation": disc, "N": 32}), kernels={"linear"})
        errs[disc] = abs(run_modes(system, {"count": 1}, {})["frequencies"][0] / low[0] - 1)
    assert errs["lagrange2"] < 1e-4 < errs["lagrange1"]


def _timoshenko_pinned_pinned(kGA: float, rhoI: float, n: int, EI=1.0, rhoA=1.0, L=1.0) -> float:
    """Lower root of the pinned-pinned Timoshenko frequency equation (k = n pi / L):
    (rhoA rhoI / kGA) w^4 - (rhoA + rhoI k^2 + rhoA EI k^2 / kGA) w^2 + EI k^4 = 0, in the form
    w^2 = 2c / (-b + sqrt(b^2 - 4ac)) that does not cancel when kGA is huge."""
    k = n * np.pi / L
    a, b, c = rhoA * rhoI / kGA, -(rhoA + rhoI * k**2 + rhoA * EI * k**2 / kGA), EI * k**4
    return float(np.sqrt(2 * c / (-b + np.sqrt(b * b - 4 * a * c))))


def test_extreme_shear_stiffness_converges_or_warns_instead_of_silent_garbage():
    """Hard case: kGA/EI = 1e9 with rhoI = 1e-9 spans 4e13 in eigenvalue (K phi = lambda M phi loses ~1e-2 to
    round-off: 8 % measured on the first mode). Pinned-pinned, K is positive definite and modes() solves for
    mu = 1/omega^2, which keeps the low modes to round-off: they converge to the Timoshenko closed form
    (measured 3.4e-8 relative with the default OpenBLAS kernel, 1.1e-7 with Haswell; bound 1e-6).
    Free-free, K is singular (rigid modes), only the direct solver is available, and modes() must say that
    its low modes are inaccurate rather than return them silently."""
    from mechgen.runtime.linear.modes import AccuracyWarning

    model = models.get("timoshenko_beam")
    hard = {"discretisation": "legendre", "N": 20, "kGA": 1e9, "rhoI": 1e-9}
    system, _ = compile_model(model, specialize(model, hard), kernels={"linear"})
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        out = run_modes(system, {"count": 3}, {})
    exact = [_timoshenko_pinned_pinned(1e9, 1e-9, n) for n in (1, 2, 3)]
    assert out["frequencies"] == pytest.approx(exact, rel=1e-6)
    free, _ = compile_model(model, specialize(model, {**hard, "bc": "free-free"}), kernels={"linear"})
    with pytest.warns(AccuracyWarning, match="accurate only to"):
        run_modes(free, {"count": 3}, {})
