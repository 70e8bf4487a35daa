"""Euler-Bernoulli beam discretised every way against the exact frequencies, with convergence rates.

Reference: omega_n = (beta_n L)^2 sqrt(EI / (rhoA L^4)) with beta_n L the roots of the
frequency equations (Blevins, Formulas for Natural Frequency and Mode Shape, 1979,
Table 8-1): sin(beta L) = 0 (pinned-pinned), cos(beta L) cosh(beta L) = 1
(clamped-clamped), cos(beta L) cosh(beta L) = -1 (clamped-free). The roots are
recomputed here to 1e-14 by brentq on those equations, independent of mechgen.
"""
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.errors import InputError
from mechgen.runtime.linear.modes import modes
from mechgen.symbolic.specialize import specialize

EQUATIONS = {
    "pinned-pinned": lambda x: np.sin(x),
    "clamped-clamped": lambda x: np.cos(x) * np.cosh(x) - 1.0,
    "clamped-free": lambda x: np.cos(x) * np.cosh(x) + 1.0,
}


def exact_roots(bc: str, count: int = 5) -> np.ndarray:
    """beta_n L from the frequency equation (scaled by exp(-x) to stay finite)."""
    f = EQUATIONS[bc]
    g = (lambda x: f(x) * np.exp(-x)) if bc != "pinned-pinned" else f
    roots = []
    for n in range(1, count + 1):
        lo, hi = (n - 0.5) * np.pi + 0.01, (n + 0.5) * np.pi
        if bc == "pinned-pinned":
            lo, hi = n * np.pi - 0.5, n * np.pi + 0.5
        elif bc == "clamped-free":
            lo, hi = (n - 0.5) * np.pi - 0.5, (n - 0.5) * np.pi + 0.4
        else:
            lo, hi = (n + 0.5) * np.pi - 0.2, (n + 0.5) * np.pi + 0.2
        roots.append(brentq(g, lo, hi, xtol=1e-15))
    return np.array(roots)


def beam_frequencies(bc, disc, size, *, backend="c", count=5, constraints="eliminate", **params):
    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"bc": bc, "discretisation": disc, "N": size, "constraints": constraints, **params})
    system, _ = compile_model(model, spec, kernels={"linear"}, backend=backend)
    mats = system.linear()
    return modes(mats["M"], mats["K"], count=count, allow_singular_mass=system.has_multipliers).frequencies


def test_exact_roots_are_the_tabulated_ones():
    # Blevins Table 8-1, first roots to the printed digits
    assert exact_roots("clamped-clamped")[0] == pytest.approx(4.73004074, abs=1e-8)
    assert exact_roots("clamped-free")[0] == pytest.approx(1.87510407, abs=1e-8)
    assert exact_roots("clamped-free")[1] == pytest.approx(4.69409113, abs=1e-8)


# (discretisation, size, relative error bound on the first five frequencies)
CASES = [("hermite", 64, 1e-5), ("quintic", 16, 1e-7), ("legendre", 24, 1e-8), ("beam", 8, 1e-12)]


@pytest.mark.parametrize("bc", list(EQUATIONS))
@pytest.mark.parametrize("disc,size,bound", CASES)
def test_beam_frequencies(bc, disc, size, bound):
    omega = exact_roots(bc) ** 2
    err = np.abs(beam_frequencies(bc, disc, size) / omega - 1)
    assert err.max() < bound


def test_sine_basis_is_exact_for_pinned_beam():
    omega = (np.arange(1, 6) * np.pi) ** 2
    assert np.abs(beam_frequencies("pinned-pinned", "sine", 20) / omega - 1).max() < 1e-11


@pytest.mark.parametrize("disc,rate", [("hermite", 4.0), ("quintic", 8.0)])
def test_element_convergence_rate(disc, rate):
    """Frequency error O(h^(2(p+1-m))): h^4 for cubic Hermite, h^8 for the quintic (m = 2)."""
    sizes = np.array([4, 8, 16]) if disc == "quintic" else np.array([8, 16, 32])
    omega = exact_roots("clamped-free", 3) ** 2
    errors = [abs(beam_frequencies("clamped-free", disc, n, count=3)[2] / omega[2] - 1) for n in sizes]
    slope = -np.polyfit(np.log(sizes), np.log(errors), 1)[0]
    assert slope == pytest.approx(rate, abs=0.3)


def test_penalty_converges_to_elimination():
    """The penalty method (seed 002) matches elimination to the accuracy its rule states.

    The bound 1e-8 this test had held only by round-off luck on one BLAS kernel (the factor 1e6 put the
    spectrum's span at 6e13, eps * 6e13 = 1e-2; under OPENBLAS_CORETYPE=Haswell the error was 34 %).
    The rule (mechgen.runtime.fields.constrain.penalty_choice) balances the penalty error P/f against the
    round-off: it predicts a lowest-eigenvalue error of P/f (frequency: half), here 1.7e-7, and the
    penalty error of mode i grows with its reaction, ~omega_i / omega_1 (1.2e-5 at the fifth)."""
    exact = beam_frequencies("clamped-free", "hermite", 32)
    penalised = beam_frequencies("clamped-free", "hermite", 32, constraints="penalty")
    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"bc": "clamped-free", "discretisation": "hermite", "N": 32, "constraints": "penalty"})
    choice = compile_model(model, spec, kernels={"linear"})[0].penalty_choice
    err = np.abs(penalised / exact - 1)
    assert err[0] == pytest.approx(choice.P / choice.factor / 2, rel=0.05)
    assert np.all(err < 1.5 * err[0] * exact / exact[0])


def test_penalty_refused_for_global_bases():
    with pytest.raises(InputError, match="penalty"):
        beam_frequencies("clamped-clamped", "legendre", 12, constraints="penalty")


@pytest.mark.parametrize("backend", ["numpy", "casadi"])
def test_backends_agree(backend):
    ref = beam_frequencies("clamped-clamped", "quintic", 8)
    assert np.allclose(beam_frequencies("clamped-clamped", "quintic", 8, backend=backend), ref, rtol=1e-12)


def test_static_deflection_under_uniform_load():
    """Pinned-pinned, uniform q: total potential -q^2 L^5 / (240 EI), midspan 5 q L^4 / (384 EI) (closed form).

    The exact deflection is a quartic, which quintic elements represent exactly.
    """
    from mechgen.analyses.steady import run_steady

    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"discretisation": "quintic", "N": 2, "q": 3.0, "EI": 2.0, "L": 1.5})
    system, _ = compile_model(model, spec, kernels={"residual", "tangent", "outputs"})
    out = run_steady(system, {"tol": 1e-12}, {})
    assert out["potential_energy"] == pytest.approx(-3.0**2 * 1.5**5 / (240 * 2.0), rel=1e-12)
    x = system.reduction.expand(out["_q"])
    mid = system.disc.row("w", 0, 0.75) @ x
    assert mid == pytest.approx(5 * 3.0 * 1.5**4 / (384 * 2.0), rel=1e-12)


def test_c0_elements_refuse_curvature_energies():
    with pytest.raises(InputError, match="C0"):
        beam_frequencies("pinned-pinned", "lagrange2", 8)


def test_sine_basis_refuses_a_free_end():
    with pytest.raises(InputError, match="free at the end"):
        beam_frequencies("clamped-free", "sine", 8)


def test_under_integration_is_refused():
    """64 Gauss points for 60 sines (products up to wavenumber 120 pi / L need 2 N + 2 = 122) leave a 15 % mass
    error: refused at params.quadrature (exit 2), not run with a warning; the automatic rule is exact."""
    from mechgen.errors import InputError

    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"discretisation": "sine", "N": 60, "quadrature": 64})
    system, _ = compile_model(model, spec, kernels={"linear"})
    with pytest.raises(InputError) as err:
        system.linear()
    assert err.value.key == "params.quadrature" and "at least 122" in str(err.value)
    spec = specialize(model, {"discretisation": "sine", "N": 60})
    system, _ = compile_model(model, spec, kernels={"linear"})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mats = system.linear()
    assert np.allclose(np.diag(mats["M"]), 0.5, rtol=1e-13)  # int sin^2 = L/2, exact with 2N + 8 points


@pytest.mark.parametrize("bc,reactions,peak", [
    # uniform load q on span L: the standard beam-table results (e.g. Roark, Formulas for Stress and Strain, Table 8.1)
    ("pinned-pinned", [("w", "start", 0.5), ("w", "end", 0.5)], 5 / 384),
    ("clamped-free", [("w", "start", 1.0), ("w_s", "start", 0.5)], 1 / 8),
    ("clamped-clamped", [("w", "start", 0.5), ("w_s", "start", 1 / 12), ("w", "end", 0.5), ("w_s", "end", -1 / 12)],
     1 / 384),
])
def test_reactions_and_deflection_under_uniform_load(bc, reactions, peak):
    """Support forces (x q L) and moments (x q L^2), peak deflection (x q L^4 / EI): beam-table closed forms."""
    from mechgen.analyses.steady import run_steady

    q, L, EI = 2.0, 1.5, 3.0
    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"discretisation": "quintic", "N": 4, "q": q, "EI": EI, "L": L, "bc": bc})
    system, _ = compile_model(model, spec, kernels={"residual", "tangent", "outputs"})
    out = run_steady(system, {"tol": 1e-12}, {})
    got = [(r["jet"], r["at"], r["value"]) for r in out["reactions"]]
    assert [g[:2] for g in got] == [r[:2] for r in reactions]
    for (jet, _, value), (_, _, factor) in zip(got, reactions):
        assert value == pytest.approx(factor * q * L ** (2 if jet == "w_s" else 1), rel=1e-10)
    assert max(out["deflection"]["w"]) == pytest.approx(peak * q * L**4 / EI, rel=1e-9)


def test_free_vibration_in_the_first_mode_returns_after_one_period():
    """simulate: started in mode 1 (a standing wave), the cantilever is back after 2 pi / omega_1.

    omega_1 = 1.8751^2 sqrt(EI / rhoA L^4); quintic elements (N = 2) are within 1e-7 of it.
    """
    from mechgen.runtime.core.integrate import integrate_first_order
    from mechgen.analyses.simulate import initial_state, run_simulate

    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"discretisation": "quintic", "N": 2, "bc": "clamped-free"})
    system, _ = compile_model(model, spec, kernels={"residual", "tangent", "outputs", "linear"})
    period = 2 * np.pi / exact_roots("clamped-free", 1)[0] ** 2
    q0, v0 = initial_state(system, {"initial_mode": 1, "amplitude": 0.1})
    traj = integrate_first_order(system.rhs, np.concatenate([q0, v0]), period, jac=system.jacobian, method="Radau",
                                 rtol=1e-9, atol=1e-12)
    xs = traj.x if traj.x.shape[0] == len(traj.t) else traj.x.T
    assert np.abs(xs[-1, :system.n] - q0).max() < 1e-6 * np.abs(q0).max()
    out = run_simulate(system, {"t_end": period, "initial_mode": 1, "amplitude": 0.1, "method": "Radau",
                                "rtol": 1e-9, "atol": 1e-12, "samples": 11, "outputs": ["energy"]}, {})
    assert out["energy_drift"] < 1e-7


@pytest.mark.parametrize("disc,size", [("hermite", 32), ("legendre", 20), ("hermite", 150)])
def test_lagrange_multipliers_match_elimination(disc, size):
    """Bordered [[K, C^T], [C, 0]] with a massless multiplier block: the same constrained frequencies
    (QZ on the singular-mass pencil, or shift-invert for the 300-unknown case)."""
    exact = beam_frequencies("clamped-free", disc, size)
    bordered = beam_frequencies("clamped-free", disc, size, constraints="multiplier")
    assert np.abs(bordered / exact - 1).max() < 1e-7


def test_multipliers_are_the_reactions():
    """Clamped-free under uniform q: the multipliers solved by Newton are R = q L and M = q L^2 / 2."""
    from mechgen.analyses.steady import run_steady

    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"discretisation": "quintic", "N": 4, "q": 2.0, "bc": "clamped-free",
                              "constraints": "multiplier"})
    system, _ = compile_model(model, spec, kernels={"residual", "tangent", "outputs"})
    out = run_steady(system, {"tol": 1e-12}, {})
    assert np.allclose(out["_q"][-2:], [2.0, 1.0], rtol=1e-10)
    assert [r["value"] for r in out["reactions"]] == pytest.approx([2.0, 1.0], rel=1e-10)
    assert max(out["deflection"]["w"]) == pytest.approx(2.0 / 8, rel=1e-10)


def test_multipliers_refuse_time_integration():
    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"N": 4, "bc": "clamped-free", "constraints": "multiplier"})
    system, _ = compile_model(model, spec, kernels={"residual", "tangent", "outputs"})
    with pytest.raises(InputError, match="DAE"):
        system.rhs(0.0, np.zeros(2 * system.n))
