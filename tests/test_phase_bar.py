"""Phase boundaries in a bar (issue 28, items 7-9): Maxwell stress, two-phase equilibria, driving traction.

References (Abeyaratne & Knowles, J. Mech. Phys. Solids 38, 1990; "Evolution of Phase Transitions", CUP 2006):

* cubic law sigma = mu (gamma - beta gamma^2 + c gamma^3): a cubic is point-symmetric about its inflection
  gamma_i = beta/(3 c) (sigma(gamma_i + u) - sigma(gamma_i) = sigma'(gamma_i) u + mu c u^3 is odd in u), so the
  horizontal line through (gamma_i, sigma(gamma_i)) cuts equal areas: sigma_M = sigma(gamma_i)
  = mu (beta/(3 c) - 2 beta^3/(27 c^2)), phase strains gamma_i -+ sqrt((beta^2 - 3 c)/(3 c^2)) (the roots of
  sigma'(gamma_i) + mu c u^2 = 0);
* trilinear law: an equal-area solve written here with scipy (quad of a hand-written sigma, brentq), independent
  of the model's kernels and of mechgen.runtime.steady.phases; with both phases of modulus mu the driving
  traction is f = gamma_T (sigma - sigma_M) in closed form;
* a convex law (beta^2 < 3 c) has no phase boundary.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import mechgen
from mechgen.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def trilinear():
    """The trilinear law with every numeric parameter free (one compilation; with_params for the variants)."""
    return mechgen.compile("phase_bar", {"law": "trilinear"}, backend="c")


def _scene_outputs(name: str) -> tuple[dict, dict]:
    run = mechgen.run(str(ROOT / "scenes" / name))
    return run["params"], {a["name"]: a["outputs"] for a in run["analyses"]}


@pytest.fixture(scope="module")
def cubic_scene():
    return _scene_outputs("phase_bar_cubic.toml")


def test_cubic_maxwell_stress_is_the_stress_at_the_inflection(cubic_scene):
    p, out = cubic_scene
    mu, beta, c = p["mu"], p["beta"], p["c"]
    r = out["maxwell"]
    gi = beta / (3 * c)
    sigma_m = mu * (beta / (3 * c) - 2 * beta**3 / (27 * c**2))
    u = np.sqrt((beta**2 - 3 * c) / (3 * c**2))
    assert r["phase_boundary"]
    # Brent's method to 1e-15 of the stress scale on a kernel evaluated in double precision
    assert abs(r["maxwell_stress"] - sigma_m) <= 1e-11 * mu
    np.testing.assert_allclose(r["phase_strains"], [gi - u, gi + u], rtol=0, atol=1e-9)  # sigma' ~ 1: same digits
    # the spinodal: sigma' = mu (1 - 2 beta gamma + 3 c gamma^2) = 0
    roots = np.sort(np.roots([3 * c, -2 * beta, 1.0]))
    np.testing.assert_allclose(r["spinodal_strains"], roots, rtol=0, atol=1e-12)


def _cubic_plateau(p: dict) -> float:
    """The loading plateau of the cubic law under power kinetics, solved here with numpy's cubic roots: the stress
    at which V = V0 (f/f0)^m, f = W(g1) - W(g2) - sigma (g1 - g2), equals rate/(g2 - g1) (the boundary keeping pace
    with the ramp at fixed phase strains: d delta/dt = V (g2 - g1))."""
    mu, beta, c = p["mu"], p["beta"], p["c"]

    def W(g):
        return mu * (g**2 / 2 - beta * g**3 / 3 + c * g**4 / 4)

    def gap(sigma):
        roots = np.sort(np.roots([mu * c, -mu * beta, mu, -sigma]).real)
        g1, g2 = roots[0], roots[2]
        f = W(g1) - W(g2) - sigma * (g1 - g2)
        return p["V0"] * np.sign(f) * abs(f / p["f0"])**p["exponent"] - p["rate"] / (g2 - g1)

    gi = beta / (3 * c)
    sigma_m = mu * (gi - beta * gi**2 + c * gi**3)
    return brentq(gap, sigma_m + 1e-9, p["sigma_nucleation"], xtol=1e-15)


def test_cubic_power_kinetics_plateau_and_dissipation_identity(cubic_scene):
    p, out = cubic_scene
    k = out["kinetics"]
    assert [e["guard"] for e in k["events"]] == ["nucleation", "arrival", "turn", "reversion", "retreat"]
    assert abs(k["dissipation_residual"]) <= 1e-10 * abs(k["work"])  # integrals carried at rtol 1e-10
    assert min(np.array(k["driving_traction"]) * np.gradient(k["s"], k["t"])) >= 0.0  # f V >= 0: phi odd
    t, stress = np.array(k["t"]), np.array(k["stress"])
    middle = (t > k["nucleation_time"] + 2.0) & (t < k["arrival_time"] - 0.5)
    assert middle.sum() > 100
    plateau = _cubic_plateau(p)
    # the state's error (rtol 1e-10) and the plateau's approach (relaxed within 2 s of nucleation)
    assert np.max(np.abs(stress[middle] - plateau)) <= 1e-7 * plateau


def _trilinear(g, gM, gm, gT):
    """sigma/mu of the trilinear law, written out here."""
    if g <= gM:
        return g
    if g < gm:
        return gM + ((gm - gT) - gM) * (g - gM) / (gm - gM)
    return g - gT


@pytest.mark.slow
def test_trilinear_maxwell_stress_against_an_independent_equal_area_solve(trilinear):
    gM, gm, gT = 0.02, 0.07, 0.06
    r = mechgen.phase_boundary(trilinear.with_params(gamma_M=gM, gamma_m=gm, gamma_T=gT), strain_range=[-0.01, 0.12])

    def area(sigma):  # int_{g1}^{g2} (sigma(g) - sigma) dg with g1 = sigma, g2 = sigma + gT (mu = 1)
        return quad(lambda g: _trilinear(g, gM, gm, gT) - sigma, sigma, sigma + gT, points=[gM, gm],
                    epsabs=1e-15, epsrel=1e-13)[0]

    reference = brentq(area, gm - gT, gM, xtol=1e-15)
    assert abs(r["maxwell_stress"] - reference) <= 1e-12  # quad's and brentq's tolerances, stresses ~ 0.02
    np.testing.assert_allclose(r["phase_strains"], [reference, reference + gT], rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["spinodal_strains"], [gM, gm], rtol=0, atol=1e-12)  # the kinks, by Brent


def test_two_phase_equilibria_fractions_and_driving_traction(trilinear):
    gM, gm, gT, L = 0.02, 0.06, 0.05, 2.0
    r = mechgen.phase_boundary(trilinear.with_params(gamma_M=gM, gamma_m=gm, gamma_T=gT, L=L), strain_range=[-0.01, 0.1],
                               elongation=[0.08, 0.01], equilibrium_samples=9)
    sigma_m = r["maxwell_stress"]
    w0 = gM**2 / 2 + gM * (gm - gM) + ((gm - gT) - gM) / (gm - gM) * (gm - gM)**2 / 2 - (gm - gT)**2 / 2
    assert abs(sigma_m - w0 / gT) <= 1e-13  # sigma_M = w0/gamma_T (the model's docstring)
    inside, outside = r["equilibria"]
    nu = (0.08 / L - sigma_m) / gT  # phase strains sigma_M and sigma_M + gamma_T
    assert abs(inside["phase_fraction"] - nu) <= 1e-12 and abs(inside["boundary_position"] - nu * L) <= 1e-12
    assert abs(inside["driving_traction"]) <= 1e-15  # f = 0 at the Maxwell stress (stresses ~ 0.02)
    assert outside["phase_fraction"] is None  # mean strain 0.005 < gamma_1: one phase
    fam = inside["family"]
    assert len(fam["stress"]) > 3
    np.testing.assert_allclose(fam["driving_traction"], gT * (np.array(fam["stress"]) - sigma_m), rtol=0, atol=1e-15)
    np.testing.assert_allclose(fam["phase_fraction"], (0.08 / L - np.array(fam["stress"])) / gT, rtol=0, atol=1e-12)


def test_a_convex_energy_has_no_phase_boundary_and_says_so(trilinear):
    # gamma_m - gamma_T = 0.03 > gamma_M: the "falling" branch rises, W is convex (slopes mu, 0.25 mu, mu)
    r = mechgen.phase_boundary(trilinear.with_params(gamma_T=0.03), strain_range=[-0.01, 0.1], elongation=[0.04])
    assert r["phase_boundary"] is False and r["maxwell_stress"] is None
    assert r["phase_strains"] == [] and r["equilibria"] == []
    assert "convex" in r["note"] and "no phase boundary" in r["note"]


def test_a_convex_cubic_law_says_no_phase_boundary_and_its_kinetic_run_is_refused(capsys):
    # beta^2 = 1 < 3 c = 6.6: sigma increasing, W convex
    scene = str(ROOT / "scenes" / "phase_bar_cubic.toml")
    assert main(["run", scene, "--set", "beta=1.0", "--set", "kinetics=linear"]) == 2
    captured = capsys.readouterr()
    assert "convex there, so no phase boundary" in captured.out
    assert "phase_bar_cubic.toml" in captured.err and "'params'" in captured.err and "beta^2 > 3 c" in captured.err


def _scene(tmp_path, *edits) -> Path:
    text = (ROOT / "scenes" / "phase_bar.toml").read_text()
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "bar.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("edit, words", [
    (('law = "trilinear"', 'law = "quartic"'), ["law", "cubic", "trilinear"]),
    (("strain_range = [-0.01, 0.1]", "strain_range = [0.0, 0.05]"), ["strain_range", "wider"]),
    (("strain_range = [-0.01, 0.1]", "strain_range = [0.1, -0.01]"), ["strain_range", "increasing"]),
])
def test_bad_input_is_refused_naming_file_and_key(tmp_path, capsys, edit, words):
    path = _scene(tmp_path, edit)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert "bar.toml" in err or words[0] == "params"
    for word in words:
        assert word in err, err


# --------------------------------------------------------------------------- kinetics (item 8)
#
# Trilinear law, both phases of modulus mu, phase 2 on 0 < x < s: the stress is affine in s and delta,
# sigma = mu (delta - gamma_T s)/L (from s (sigma/mu + gamma_T) + (L - s) sigma/mu = delta), and
# f = gamma_T (sigma - sigma_M), so linear kinetics ds/dt = f/eta is the linear ODE
#     ds/dt + k s = (gamma_T/eta) (mu delta(t)/L - sigma_M),   k = mu gamma_T^2/(L eta).
# For a ramp delta = delta_0 + r (t - t_0) the right side is a + b (t - t_0) with a = (gamma_T/eta)(mu delta_0/L -
# sigma_M), b = gamma_T mu r/(L eta); its solution from s(t_0) = s_0 is
#     s(t) = p(t) + (s_0 - p(t_0)) exp(-k (t - t_0)),   p(t) = (a - b/k)/k + (b/k) (t - t_0).
# Nucleation at sigma_nucleation on the way up: t_n = L sigma_nucleation/(mu r), s = 0; reversion at
# sigma_reversion on the way down (all phase 2: sigma = mu (delta/L - gamma_T)): delta_r = L (sigma_reversion/mu +
# gamma_T), t_r = 2 t_turn - delta_r/r, s = L.

def _scene_run():
    run = mechgen.run(str(ROOT / "scenes" / "phase_bar.toml"))
    return run["params"], {a["name"]: a["outputs"] for a in run["analyses"]}["kinetics"]


def _segment(p, t0, s0, delta0, r):
    """s(t) on a ramp from (t0, s0, delta0) at rate r (the closed form above)."""
    mu, gT, L, eta, sigma_m = p["mu"], p["gamma_T"], p["L"], p["eta"], p["_sigma_m"]
    k = mu * gT**2 / (L * eta)
    a, b = gT / eta * (mu * delta0 / L - sigma_m), gT * mu * r / (L * eta)
    return lambda t: (a - b / k) / k + b / k * (t - t0) + (s0 - (a - b / k) / k) * np.exp(-k * (t - t0))


@pytest.fixture(scope="module")
def kinetics():
    p, k = _scene_run()
    gM, gm, gT = p["gamma_M"], p["gamma_m"], p["gamma_T"]
    p["_sigma_m"] = p["mu"] * (gM**2 / 2 + gM * (gm - gM) + ((gm - gT) - gM) * (gm - gM) / 2 - (gm - gT)**2 / 2) / gT
    return p, k


def test_boundary_position_and_event_times_against_the_closed_form(kinetics):
    p, k = kinetics
    mu, L, r, T = p["mu"], p["L"], p["rate"], p["t_turn"]
    t_n = L * p["sigma_nucleation"] / (mu * r)
    up = _segment(p, t_n, 0.0, r * t_n, r)
    t_a = brentq(lambda t: up(t) - L, t_n + 1e-9, T)
    delta_r = L * (p["sigma_reversion"] / mu + p["gamma_T"])
    t_r = 2 * T - delta_r / r
    down = _segment(p, t_r, L, delta_r, -r)
    t_b = brentq(lambda t: down(t), t_r + 1e-9, 2 * T)
    # events located to the integrator's accuracy (rtol 1e-10, atol 1e-12: measured 2e-12 s on times ~ 10 s)
    for key, ref in (("nucleation_time", t_n), ("arrival_time", t_a), ("reversion_time", t_r), ("retreat_time", t_b)):
        assert abs(k[key] - ref) <= 1e-9, (key, k[key], ref)
    t, s = np.array(k["t"]), np.array(k["s"])
    reference = np.where(t < t_n, 0.0, np.where(t < t_a, up(t), np.where(t < t_r, L, np.where(t < t_b, down(t), 0.0))))
    near = np.min(np.abs(t[:, None] - np.array([t_n, t_a, t_r, t_b])[None, :]), axis=1) < 1e-6  # a sample on an event
    assert np.count_nonzero(~near) > 300
    assert np.max(np.abs(s - reference)[~near]) <= 1e-9 * L  # rtol 1e-10, atol 1e-12 over 20 s (measured 2e-11)


def test_dissipation_identity_and_the_closed_form_dissipation(kinetics):
    p, k = kinetics
    scale = abs(k["work"])
    assert abs(k["dissipation_residual"]) <= 1e-10 * scale  # integrated with the state at rtol 1e-10
    assert abs(k["stored_energy_change"]) <= 1e-12 * scale  # back to delta = 0, all phase 1, E = 0
    # int f V dt = int gamma_T^2 (sigma - sigma_M)^2/eta dt with sigma = mu (delta - gamma_T s)/L, s in closed form
    mu, gT, L, eta, r, T = p["mu"], p["gamma_T"], p["L"], p["eta"], p["rate"], p["t_turn"]
    t_n, t_a, t_r, t_b = (k[key] for key in ("nucleation_time", "arrival_time", "reversion_time", "retreat_time"))
    up, down = _segment(p, t_n, 0.0, r * t_n, r), _segment(p, t_r, L, r * (2 * T - t_r), -r)

    def rate(t, seg, delta):
        sigma = mu * (delta(t) - gT * seg(t)) / L
        return gT**2 * (sigma - p["_sigma_m"])**2 / eta

    total = quad(rate, t_n, t_a, args=(up, lambda t: r * t), epsabs=0, epsrel=1e-12, limit=200)[0] + \
        quad(rate, t_r, t_b, args=(down, lambda t: r * (2 * T - t)), epsabs=0, epsrel=1e-12, limit=200)[0]
    assert abs(k["dissipated"] - total) <= 1e-8 * total  # the integrator's rtol 1e-10 and quad's 1e-12, with margin
    # the loop: on the plateaus sigma -> sigma_M + eta r/gamma_T^2 (loading) and sigma_M - eta r/gamma_T^2
    t, stress = np.array(k["t"]), np.array(k["stress"])
    plateau = p["_sigma_m"] + eta * r / gT**2
    assert abs(stress[np.argmin(np.abs(t - (t_a - 0.5)))] - plateau) <= 1e-8


def test_trilinear_law_with_gamma_m_below_gamma_M_is_refused(trilinear):
    with pytest.raises(mechgen.InputError, match="gamma_M < gamma_m") as info:
        mechgen.phase_boundary(trilinear.with_params(gamma_m=0.01), strain_range=[-0.01, 0.1])
    assert info.value.key == "params"


@pytest.mark.parametrize("values, key", [
    ({"sigma_nucleation": 0.025}, "params.sigma_nucleation"),  # above the peak 0.02: never nucleates
    ({"sigma_reversion": 0.016}, "params.sigma_reversion"),  # above sigma_M = 0.015: phase 1 would shrink
    ({"eta": 0.1}, "params.eta"),  # the boundary too slow: phase 1 strained onto the falling branch
    ({"gamma_T": 0.03}, "params"),  # a convex law
])
def test_kinetics_bad_input_is_refused_at_the_key(trilinear, values, key):
    system = trilinear.with_params(eta=5e-4, sigma_nucleation=0.018, sigma_reversion=0.012, rate=0.01, t_turn=10.0)
    with pytest.raises(mechgen.InputError) as info:
        mechgen.phase_kinetics(system.with_params(**values), t_end=20.0, strain_range=[-0.01, 0.1])
    assert info.value.key == key, str(info.value)


def test_runtime_phases_on_a_hand_written_double_well():
    """mechgen.runtime.steady.phases on numpy functions alone (no kernels): W = g^4/4 - g^2/2 + a g, sigma = g^3 - g
    + a; a shifts the stress only, so sigma_M = a, the phase strains are -1 and 1 and the spinodal -+1/sqrt(3)."""
    from mechgen.runtime.steady import phases

    a = 0.3
    stress = lambda g: np.asarray(g) ** 3 - np.asarray(g) + a  # noqa: E731
    energy = lambda g: np.asarray(g) ** 4 / 4 - np.asarray(g) ** 2 / 2 + a * np.asarray(g)  # noqa: E731
    modulus = lambda g: 3 * np.asarray(g) ** 2 - 1  # noqa: E731
    grid = np.linspace(-2.0, 2.0, 401)
    sp_ = phases.spinodal(stress, modulus, grid)
    np.testing.assert_allclose([sp_.gamma_a, sp_.gamma_b], [-1 / np.sqrt(3), 1 / np.sqrt(3)], rtol=0, atol=1e-14)
    m = phases.maxwell(stress, energy, sp_, -2.0, 2.0)
    assert abs(m.stress - a) <= 1e-14 and abs(m.gamma_1 + 1) <= 1e-13 and abs(m.gamma_2 - 1) <= 1e-13
    eq = phases.equilibria(stress, energy, sp_, -2.0, 2.0, 0.0, 5)
    g1 = [np.sort(np.roots([1, 0, -1, a - s]).real)[0] for s in eq["stress"]]
    g2 = [np.sort(np.roots([1, 0, -1, a - s]).real)[2] for s in eq["stress"]]
    np.testing.assert_allclose(eq["phase_fraction"], [-x / (y - x) for x, y in zip(g1, g2)], rtol=0, atol=1e-12)
    assert phases.spinodal(lambda g: np.asarray(g) ** 3 + np.asarray(g), None, grid) is None  # convex: none
