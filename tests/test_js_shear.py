"""Johnson-Segalman fluid in homogeneous shear (issue 28 item 2; seed 002, Khayat & Ashrafi, eq. 4).

References: the steady shear curve T(g) = epsilon g + g / (1 + xi (2 - xi) g^2), written out again here and
its extrema found by scipy's bounded scalar minimiser (independent of the closed-form roots of dT/dg = 0);
the monotonicity threshold epsilon = 1/8 (min over x of (1 - x^2)/(1 + x^2)^2 is -1/8 at x^2 = 3); the
continuation's folds against those extrema; the Jacobian of the generated rates kernel at the folds
(an eigenvalue zero) and along the branch (the eigenvalue -1 of the off-manifold combination, the other pair's
sum -2 - 1/(epsilon (1 + k g^2)): no Hopf point).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

import mechgen
from mechgen.runtime.fluids import johnson_segalman as js
from mechgen.scene.run import run_scene

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "js_shear.toml"


def shear_stress(g, epsilon, xi):
    """The seed's eq. 4, written out independently of mechgen."""
    return epsilon * g + g / (1 + xi * (2 - xi) * g**2)


@pytest.fixture(scope="module")
def scene():
    return {a["name"]: a["outputs"] for a in run_scene(str(SCENE))["analyses"]}


@pytest.mark.parametrize("epsilon, xi", [(0.06, 0.2), (0.08, 0.2), (0.01, 1.0), (0.12, 0.5)])
def test_extrema_against_a_scalar_optimiser(epsilon, xi):
    (g_max, T_max), (g_min, T_min) = js.extrema(epsilon, xi)
    x3 = np.sqrt(3 / (xi * (2 - xi)))  # the inflection of the polymer part lies between the extrema
    top = minimize_scalar(lambda g: -shear_stress(g, epsilon, xi), bounds=(0, x3), method="bounded",
                          options={"xatol": 1e-12})
    low = minimize_scalar(lambda g: shear_stress(g, epsilon, xi), bounds=(x3, 100 * x3), method="bounded",
                          options={"xatol": 1e-12})
    # the optimiser locates a flat extremum's abscissa to sqrt(machine eps) relative; its value to round-off
    assert abs(g_max - top.x) < 1e-6 * g_max and abs(g_min - low.x) < 1e-6 * g_min
    assert abs(T_max + top.fun) < 1e-12 and abs(T_min - low.fun) < 1e-12


def test_one_eighth_threshold():
    """Monotone at and above epsilon = 1/8 (no extrema), non-monotone just below with both extrema merging at
    x^2 = 3; the least slope over a fine grid is >= 0 exactly from 1/8 on."""
    xi = 0.2
    k = xi * (2 - xi)
    assert js.extrema(0.125, xi) is None and js.extrema(0.2, xi) is None and js.extrema(0.06, 0.0) is None
    (g_max, _), (g_min, _) = js.extrema(0.125 - 1e-8, xi)
    assert abs(g_max * np.sqrt(k) - np.sqrt(3)) < 1e-2 and abs(g_min * np.sqrt(k) - np.sqrt(3)) < 1e-2
    g = np.linspace(0, 20, 200_001)
    slope = lambda eps: np.min(np.gradient(shear_stress(g, eps, xi), g))  # noqa: E731
    assert slope(0.125) > -1e-8 and slope(0.124) < 0  # second differences: O(h^2) = 1e-8


def test_monotone_scene_reports_no_extrema(tmp_path):
    scene = tmp_path / "mono.toml"
    scene.write_text(SCENE.read_text().replace("epsilon = 0.06", "epsilon = 0.2").replace("stop = 1.2", "stop = 0.3"))
    out = run_scene(str(scene))["analyses"]
    curve, branch = out[0]["outputs"], out[2]["outputs"]
    assert curve["monotone"] is True and "stress_max" not in curve and "monotone" in curve["note"]
    assert not [p for p in branch["special_points"] if p["type"] in ("LP", "H")]


def test_scene_extrema_and_folds(scene):
    (g_max, T_max), (g_min, T_min) = js.extrema(0.06, 0.2)
    curve = scene["curve"]
    assert curve["monotone"] is False and curve["hopf"] == "none"
    assert abs(curve["stress_max"] - T_max) < 1e-14 and abs(curve["shear_rate_min"] - g_min) < 1e-14
    folds = [p for p in scene["s_curve"]["special_points"] if p["type"] == "LP"]
    assert [p["type"] for p in scene["s_curve"]["special_points"]] == ["LP", "LP"]  # no H, no BP
    # located by the fold test function's bisection along the branch to its tolerance (1e-10 relative here)
    assert abs(folds[0]["T"] - T_max) < 1e-9 and abs(folds[0]["shear_rate"] - g_max) < 1e-6
    assert abs(folds[1]["T"] - T_min) < 1e-9 and abs(folds[1]["shear_rate"] - g_min) < 1e-6


def _jacobian(T, state):
    system = mechgen.compile("js_local", params={"epsilon": 0.06, "xi": 0.2}, free=["T"])
    return system.with_params(T=T).jacobian(0.0, np.asarray(state, dtype=float))


def test_fold_eigenvalue_zero_and_no_hopf(scene):
    """At each fold the Jacobian of the generated rates has an eigenvalue 0 (to the fold's location error);
    along the whole branch one eigenvalue is -1 and the other two sum to -2 - 1/(epsilon (1 + k g^2))."""
    for p in scene["s_curve"]["special_points"]:
        lam = np.linalg.eigvals(_jacobian(p["T"], js.polymer_stresses(p["shear_rate"], 0.2)))
        assert np.min(np.abs(lam)) < 1e-6  # the fold's rate is located to 1e-6 (above); dT/dg = 0 there
    for point in scene["s_curve"]["branch"][::10]:
        g = point["shear_rate"]
        lam = np.linalg.eigvals(_jacobian(point["T"], js.polymer_stresses(g, 0.2)))
        k = int(np.argmin(np.abs(lam + 1)))
        assert abs(lam[k] + 1) < 1e-10
        pair = np.delete(lam, k)
        assert abs(pair.sum().real - js.pair_trace(g, 0.06, 0.2)) < 1e-9 and pair.sum().real < -2


def test_reduced_two_stress_model_is_the_invariant_plane():
    """js_local_reduced (the seed's N, S form) has js_local's eigenvalues without the constant -1, at equilibria
    of the S-curve on all three branches (g below, between and above the extrema)."""
    full = mechgen.compile("js_local", params={"epsilon": 0.06, "xi": 0.2}, free=["T"])
    reduced = mechgen.compile("js_local_reduced", params={"epsilon": 0.06, "xi": 0.2}, free=["T"])
    for g in (0.5, 3.0, 9.0):
        txx, tyy, txy = js.polymer_stresses(g, 0.2)
        T = float(js.total_stress(g, 0.06, 0.2))
        lam3 = np.linalg.eigvals(full.with_params(T=T).jacobian(0.0, np.array([txx, tyy, txy])))
        lam2 = np.linalg.eigvals(reduced.with_params(T=T).jacobian(0.0, np.array([txx - tyy, txy])))
        k = int(np.argmin(np.abs(lam3 + 1)))
        rest = np.sort_complex(np.delete(lam3, k))
        assert abs(lam3[k] + 1) < 1e-12 and np.allclose(rest, np.sort_complex(lam2), rtol=0, atol=1e-12)
