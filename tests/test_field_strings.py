"""Gyroscopic strings: the axially moving string and a string spinning about its chord.

References:
* moving string, fixed ends: omega_n = (n pi / L) (c0^2 - c^2) / c0, c0 = sqrt(P / rhoA)
  (Wickert & Mote, J. Appl. Mech. 57 (1990) 738, eq. 24); all vanish at c = c0.
* string spinning at Omega about its chord, seen from the rotating frame:
  omega = omega_n +- Omega, omega_n = (n pi / L) sqrt(P / rhoA) (the inertial problem is
  isotropic; the frame rotation shifts each circular whirl by Omega).
"""
import numpy as np
import pytest

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.analyses.stability import run_stability
from mechgen.symbolic.specialize import specialize


def system_of(name, **values):
    model = models.get(name)
    system, _ = compile_model(model, specialize(model, values), kernels={"linear"})
    return system


def moving_exact(c, P=2.0, rhoA=0.5, L=1.5, count=5):
    c0 = np.sqrt(P / rhoA)
    return np.arange(1, count + 1) * np.pi / L * (c0**2 - c**2) / c0


@pytest.mark.parametrize("c", [0.0, 0.7, 1.4, 1.9])
def test_moving_string_frequencies(c):
    system = system_of("moving_string", c=c, P=2.0, rhoA=0.5, L=1.5, discretisation="legendre", N=32)
    out = run_stability(system, {"count": 5}, {})
    assert out["verdict"] == "stable"
    assert np.allclose(out["frequencies"], moving_exact(c), rtol=1e-10)


def test_moving_string_sine_galerkin_converges():
    """Sine-Galerkin truncation error falls by about 2^3 per doubling of N (gyroscopic coupling)."""
    errors = []
    for n in (16, 32, 64):
        system = system_of("moving_string", c=1.2, P=2.0, rhoA=0.5, L=1.5, discretisation="sine", N=n)
        out = run_stability(system, {"count": 3, "refine": False}, {})
        errors.append(np.abs(np.array(out["frequencies"]) / moving_exact(1.2, count=3) - 1).max())
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(rates > 2.5), rates


def test_fundamental_vanishes_at_critical_speed():
    system = system_of("moving_string", c=2.0, P=2.0, rhoA=0.5, L=1.5, discretisation="legendre", N=24)
    out = run_stability(system, {"refine": False}, {})
    moduli = np.sort(np.abs([complex(*s) for s in out["eigenvalues"]]))
    assert moduli[0] < 1e-8 * moving_exact(0.0)[0]


def test_supercritical_truncations_do_not_give_a_verdict():
    """Past c0 the Galerkin truncations flutter with growth that keeps rising under refinement: 'unconverged'."""
    system = system_of("moving_string", c=1.3, discretisation="legendre", N=16)
    out = run_stability(system, {}, {})
    assert out["verdict"] == "unconverged"
    g = out["refinement"]["growth_rates"]
    assert g[1] > 1.5 * g[0] > 0


@pytest.mark.parametrize("omega", [0.0, 1.0, 5.0])
def test_rotating_string_splits_by_the_spin(omega):
    system = system_of("rotating_string", Omega=omega, P=4.0, rhoA=1.0, L=2.0, discretisation="sine", N=12)
    out = run_stability(system, {}, {})
    wn = np.arange(1, 13) * np.pi / 2.0 * 2.0
    expected = np.unique(np.round(np.abs(np.concatenate([wn + omega, wn - omega])), 12))
    expected = expected[expected > 1e-9][:10]
    assert out["verdict"] == "stable"
    assert np.allclose(out["frequencies"][:10], expected, rtol=1e-12)


def test_rotating_string_hermite_converges_to_the_split():
    system = system_of("rotating_string", Omega=2.0, discretisation="hermite", N=40)
    out = run_stability(system, {"refine": False}, {})
    wn = np.arange(1, 6) * np.pi
    expected = np.sort(np.abs(np.concatenate([wn + 2.0, wn - 2.0])))[:4]
    assert np.allclose(out["frequencies"][:4], expected, rtol=1e-6)


def test_sparse_shift_invert_stability_of_a_large_discretisation():
    """1 200 unknowns: the lowest eigenvalues by ARPACK shift-invert equal the closed form omega_n +- Omega."""
    system = system_of("rotating_string", Omega=2.0, discretisation="hermite", N=300)
    assert system.n > 1000
    out = run_stability(system, {"count": 6}, {})
    wn = np.arange(1, 6) * np.pi
    expected = np.sort(np.abs(np.concatenate([wn + 2.0, wn - 2.0])))[:6]
    assert out["verdict"] == "stable"
    assert np.allclose(out["frequencies"], expected, rtol=1e-7)


def test_sparse_and_dense_stability_agree():
    from mechgen.runtime.linear.stability import stability, stability_sparse

    system = system_of("follower_column", P=23.0, N=24)
    mats = system.linear()
    dense = stability(*(mats[k].toarray() for k in ("M",)), (mats["D"] + mats["G"]).toarray(), mats["K"].toarray())
    sparse = stability_sparse(mats["M"], mats["D"] + mats["G"], mats["K"], 4)
    assert sparse.verdict == dense.verdict == "flutter"
    assert sparse.growth_rate == pytest.approx(dense.growth_rate, rel=1e-8)
    assert np.allclose(sparse.frequencies[:2], dense.frequencies[:2], rtol=1e-8)
