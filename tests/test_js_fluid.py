"""The Johnson-Segalman channel declared as four fields and a weak form (model js_fluid; issue 28 item 1).

References, all independent of the field machinery under test: the classical flow rate Q(G) in closed form and the
spurt threshold T_max of the local shear curve (mechgen.runtime.fluids.johnson_segalman, checked against quad in
tests/test_js_channel.py); the Oldroyd-B (xi = 0) dispersion relation Re lambda^2 + (Re + eps kappa^2) lambda +
kappa^2 (1 + eps) = 0, kappa = n pi / 2 (tests/test_js_channel_spectrum.py derives it); the Chebyshev-collocated
channel of scenes/js_channel.toml (another discretisation of the same equations); and the exact decay of the
off-manifold combination xi tau_xx + (2 - xi) tau_yy, c_t = -c + D c_ss with no-flux walls (Neumann modes
cos(m pi s / 2), decay 1 + D (m pi / 2)^2).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.errors import InputError
from mechgen.runtime.fluids import johnson_segalman as js
from mechgen.scene.run import run_scene

ROOT = Path(__file__).resolve().parents[1]
EPS, XI = 0.06, 0.2


def system(**params):
    return mechgen.compile("js_fluid", {"epsilon": EPS, "xi": XI, **params})


def spectrum(sysm) -> np.ndarray:
    out = mechgen.stability(sysm, refine=False).outputs
    return np.array([complex(*v) for v in out["eigenvalues"]])


def test_steady_flow_rate_converges_to_the_closed_form():
    """Q(G = 0.5) from Newton on the Galerkin residual against the closed form: the error falls by more than 6 per
    halving of the elements (P2 elements, O(h^3) or better) to below 1e-7 at N = 16; the wall reactions are the wall
    shear stress G (the total shear stress is G y exactly in a steady state)."""
    exact = js.flow_rate(0.5, EPS, XI)[0]
    errors = []
    for N in (4, 8, 16):
        out = mechgen.steady(system(G=0.5, N=N), tol=1e-13).outputs
        errors.append(abs(out["flow_rate"] - exact))
        assert [r["value"] for r in out["reactions"]] == pytest.approx([0.5, 0.5], abs=1e-12)
    assert errors[2] < 2e-7
    assert errors[0] / errors[1] > 6 and errors[1] / errors[2] > 6


def nearest_errors(lam: np.ndarray, references) -> np.ndarray:
    """For each reference eigenvalue, the distance to the nearest computed one."""
    return np.array([np.min(np.abs(lam - r)) for r in references])


def test_oldroyd_b_spectrum_matches_the_dispersion_relation():
    """xi = 0: the eight eigenvalues of the four lowest velocity/shear-stress modes against the closed-form roots;
    the errors fall as h^4 (P2 elements: ratio over 12 per halving) to 2e-5 relative at N = 32."""
    Re = 1.0
    roots = [r for n in range(1, 5) for r in np.roots([Re, Re + EPS * (n * np.pi / 2) ** 2,
                                                         (n * np.pi / 2) ** 2 * (1 + EPS)])]
    errors = [nearest_errors(spectrum(system(xi=0.0, Re=Re, G=0.5, N=N)), roots) / np.abs(roots) for N in (16, 32)]
    assert np.all(errors[1] < 2e-5)
    assert np.all(errors[0] / errors[1] > 12)


def test_spectrum_agrees_with_the_collocated_channel(tmp_path):
    """xi = 0.2, G = 0.5, Re = 1: the two rightmost complex pairs of the field model converge as h^4 to those of the
    Chebyshev-collocated channel (scenes/js_channel.toml, N = 48: converged to 1e-9 there), to 4e-6 at N = 32."""
    scene = tmp_path / "channel.toml"
    text = (ROOT / "scenes" / "js_channel.toml").read_text()
    scene.write_text(text.replace("discrete = true", "discrete = false"))
    out = {a["name"]: a["outputs"] for a in run_scene(str(scene))["analyses"]}["spectrum"]
    reference = np.array([complex(*v) for v in out["eigenvalues"]])[:4]
    assert reference[0].real == pytest.approx(-0.607201, abs=1e-6)
    errors = [nearest_errors(spectrum(system(G=0.5, Re=1.0, N=N)), reference) for N in (16, 32)]
    assert np.all(errors[1] < 4e-6)
    assert np.all(errors[0] / errors[1] > 12)


def test_off_manifold_combination_decays_at_exactly_minus_one():
    """Without diffusion xi tau_xx + (2 - xi) tau_yy decays at -1 at every stress node (2N + 1 of them, P2), to
    round-off; with a stress diffusivity D its Neumann modes decay at 1 + D (m pi / 2)^2: m = 0 to round-off, m = 1..3
    at the P2 Laplacian's h^4 rate (ratio over 12 per halving)."""
    N = 8
    lam = spectrum(system(G=0.5, N=N))
    assert np.count_nonzero(np.abs(lam + 1) < 1e-10) >= 2 * N + 1
    D = 0.01
    rates = [-1 - D * (m * np.pi / 2) ** 2 for m in range(4)]
    errors = [nearest_errors(spectrum(system(G=0.5, N=N, diffusion=D)), rates) for N in (16, 32)]
    assert errors[0][0] < 1e-12 and errors[1][0] < 1e-12
    assert np.all(errors[0][1:] / errors[1][1:] > 12)
    assert np.all(errors[1][1:] < 3e-6)


def test_first_fold_tends_to_the_spurt_threshold():
    """continuation in G: the first fold lies above T_max by O(h) (the wall element's shear rate reaches the maximum
    of the local curve later than the wall itself), so it halves with the element size, and the Richardson
    extrapolation of N = 16, 32 is T_max to 2e-4."""
    t_max = js.extrema(EPS, XI)[0][1]
    folds = []
    for N in (16, 32):
        sysm = system(G=0.5, N=N)
        base = mechgen.steady(sysm)
        out = mechgen.continuation(sysm, about=base, parameter="G", stop=1.0, max_points=20, stability=False,
                                   special_points=False, progress=False).outputs
        folds.append(out["folds"][0]["G"])
    errors = [f - t_max for f in folds]
    assert errors[0] > errors[1] > 0
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.05)
    assert 2 * folds[1] - folds[0] == pytest.approx(t_max, abs=2e-4)


def test_inertialess_channel_spectrum_reaches_the_band_edge():
    """Re = 0: u has no rate (its infinite eigenvalues are dropped) and the rightmost eigenvalue is the edge of the
    essential spectrum, the largest local eigenvalue over the channel (at the wall, -0.91173 from the collocated
    channel's essential_spectrum), approached from the left at first order."""
    edge = -0.911733
    rates = [spectrum(system(G=0.5, Re=0.0, N=N)).real.max() for N in (16, 32)]
    assert rates[0] < rates[1] < edge + 1e-4
    assert edge - rates[1] < 3e-3


def oldroyd_b_start_up(t: np.ndarray, G: float, Re: float, terms: int = 4000) -> np.ndarray:
    """Q(t) of the Oldroyd-B (xi = 0) channel started from rest, as a series: u = sum a_n cos(k_n y),
    tau_xy = sum b_n (cos(k_n y))', k_n = (2n - 1) pi / 2 (u = 0 at y = +-1), G = sum g_n cos(k_n y) with
    g_n = 2 G (-1)^(n+1) / k_n, so Re a' = g_n - eps k^2 a - k^2 b, b' = -b + a (the normal stresses do not feed
    back at xi = 0), each pair solved exactly by its eigenvectors; Q = sum a_n 2 (-1)^(n+1) / k_n."""
    Q = np.zeros_like(t)
    for n in range(1, terms + 1):
        k, sign = (2 * n - 1) * np.pi / 2, (-1.0) ** (n + 1)
        A = np.array([[-EPS * k**2 / Re, -k**2 / Re], [1.0, -1.0]])
        steady = -np.linalg.solve(A, [2 * G * sign / k / Re, 0.0])
        w, V = np.linalg.eig(A)
        c = np.linalg.solve(V, -steady)
        Q += (steady[0] + np.real((V[0] * c) @ np.exp(np.outer(w, t)))) * 2 * sign / k
    return Q


@pytest.mark.slow
def test_start_up_flow_matches_the_oldroyd_b_series():
    """simulate of the first-order fields from rest (BDF on q' = v(q)): Q(t) with its elastic overshoot against the
    series, at the P2 rate (over 12 per halving of the elements), 2e-7 at N = 32."""
    t = np.array([0.5, 1.0, 2.0, 5.0])
    reference = oldroyd_b_start_up(t, G=0.5, Re=1.0)
    assert reference[1] > 1.5 * 2 * 0.5 / 3 / (1 + EPS)  # the overshoot above the steady Q = 2G / (3 (1 + eps))
    errors = []
    for N in (16, 32):
        out = mechgen.simulate(system(xi=0.0, G=0.5, Re=1.0, N=N), t_end=5.0, samples=11, rtol=1e-10,
                               atol=1e-12).outputs
        assert out["method"] == "BDF"
        found = np.interp(t, out["t"], out["trajectory"]["flow_rate"])
        errors.append(np.abs(found - reference))
    assert np.all(errors[1] < 2e-7)
    assert np.all(errors[0] / errors[1] > 12)


def test_start_up_reaches_the_steady_state():
    """xi = 0.2, G = 0.5: from rest the flow settles on the steady Newton state (the slowest decay is -0.607)."""
    sysm = system(G=0.5, N=8)
    steady = mechgen.steady(sysm, tol=1e-13).outputs["flow_rate"]
    out = mechgen.simulate(sysm, t_end=40.0, samples=5).outputs
    assert out["flow_rate"] == pytest.approx(steady, abs=1e-8)


def test_inertialess_start_up_is_refused_as_a_dae():
    with pytest.raises(InputError, match="neither mass nor a rate"):
        mechgen.simulate(system(N=4, Re=0.0), t_end=0.1)
    with pytest.raises(InputError, match="first-order continuum"):
        mechgen.simulate(system(N=4), t_end=0.1, method="leapfrog", dt=0.01)


def test_scene_runs(tmp_path):
    out = {a["name"]: a["outputs"] for a in run_scene(str(ROOT / "scenes" / "js_fluid.toml"))["analyses"]}
    assert out["base"]["flow_rate"] == pytest.approx(js.flow_rate(0.5, EPS, XI)[0], abs=2e-7)
    assert out["spectrum"]["verdict"] == "stable"
    assert out["flow_curve"]["folds"][0]["G"] > js.extrema(EPS, XI)[0][1]


def test_integrated_output_needs_a_continuum():
    from mechgen import Model
    from mechgen.errors import ModelError

    lumped = Model("lumped_with_integral")
    lumped.coordinates("x")
    with pytest.raises(ModelError, match="integrated, but the model declares no continuum"):
        lumped.output("total", lambda q: q.x, integrate=True)


def test_two_stress_form_is_the_invariant_manifold():
    """js_fluid_reduced (the seed's N, S) has js_fluid's steady state (same mesh: to round-off) and its spectrum is
    js_fluid's with the 2N + 1 eigenvalues -1 of the off-manifold combination removed."""
    N = 8
    params = {"epsilon": EPS, "xi": XI, "G": 0.5, "Re": 1.0, "N": N}
    full, reduced = mechgen.compile("js_fluid", params), mechgen.compile("js_fluid_reduced", params)
    q_full = mechgen.steady(full, tol=1e-13).outputs
    q_reduced = mechgen.steady(reduced, tol=1e-13).outputs
    assert q_reduced["flow_rate"] == pytest.approx(q_full["flow_rate"], abs=1e-13)
    assert q_reduced["first_normal_stress_integral"] == pytest.approx(q_full["first_normal_stress_integral"],
                                                                      abs=1e-12)
    lam_full, lam_reduced = spectrum(full), spectrum(reduced)
    assert lam_full.size - lam_reduced.size == 2 * N + 1
    assert np.all(nearest_errors(lam_full, lam_reduced) < 1e-9)
    others = lam_full[np.abs(lam_full + 1) > 1e-9]
    assert np.all(nearest_errors(lam_reduced, others) < 1e-9)


def test_banded_states_change_stability_at_their_folds():
    """Past the spurt fold the discretised branch zigzags (the jump between the stable limbs of the local curve moves
    inward node by node): each fold is a real eigenvalue through zero, so the verdict changes at the folds and
    nowhere else, and the upper (top-jumping) pieces are stable again. The changes are located along the branch
    independently of the folds (bisection on the verdict vs the fold's turning point of G)."""
    sysm = system(G=0.5, N=8)
    out = mechgen.continuation(sysm, about=mechgen.steady(sysm), parameter="G", stop=1.0, max_points=40,
                               progress=False).outputs
    folds = [f["G"] for f in out["folds"]]
    changes = [c["G"] for c in out["stability_changes"]]
    assert len(folds) >= 2 and len(changes) == len(folds)
    assert np.allclose(changes, folds, atol=1e-6)
    first, second = out["stability_changes"][:2]
    assert (first["from"], first["to"], second["from"], second["to"]) == ("stable", "divergence", "divergence",
                                                                         "stable")
