"""Penalty constraints (mechgen.runtime.fields.constrain.penalty_choice): the rule, its convergence rate, its warning.

Reference: the same clamped-free beam with its boundary conditions eliminated (exact constraint,
no penalty). The rule's error model: the lowest eigenvalue errs by P/f (penalty, first order in
1/alpha) plus at most R f (round-off, eps times the top of the penalised spectrum), relative; a
frequency by half of it. These tests hold under every BLAS kernel (.ci/run runs them under
OPENBLAS_CORETYPE=Haswell and without it).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.runtime.fields import constrain
from mechgen.runtime.linear.modes import AccuracyWarning, modes
from mechgen.symbolic.specialize import specialize


def beam(N: int, constraints: str):
    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"bc": "clamped-free", "discretisation": "hermite", "N": N,
                              "constraints": constraints})
    return compile_model(model, spec, kernels={"linear"})[0]


def frequencies(system, count: int = 5) -> np.ndarray:
    mats = system.linear()
    return modes(mats["M"], mats["K"], count=count).frequencies


def penalty_warnings(record) -> list[str]:
    return [str(w.message) for w in record if issubclass(w.category, AccuracyWarning)
            and "penalty constraints" in str(w.message)]


@pytest.mark.parametrize("N", [32, 128])  # 128: 258 unknowns, the sparse shift-invert path
def test_default_penalty_matches_the_predicted_error_silently(N):
    exact = frequencies(beam(N, "eliminate"))
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        system = beam(N, "penalty")
        penalised = frequencies(system)
    choice = system.penalty_choice
    assert not penalty_warnings(record)
    # the balance f* = sqrt(P / R); the lowest frequency errs by (P / f*) / 2 (the round-off bound R f* is
    # a worst case the solvers stay far below), to first order in 1/alpha: 5 % covers the O(1/alpha^2)
    assert choice.factor == pytest.approx(max(1.0, np.sqrt(choice.P / choice.R)), rel=1e-12)  # f >= 1: clipped
    assert choice.predicted() == pytest.approx(choice.P / choice.factor + choice.R * choice.factor, rel=1e-12)
    assert choice.predicted() < max(constrain.PENALTY_TARGET, 4 * choice.R)
    err = penalised / exact - 1
    assert np.all(err < 0)  # a penalty is a soft support: every frequency is low
    assert -err[0] == pytest.approx(choice.P / choice.factor / 2, rel=0.05)


def test_penalty_error_falls_as_one_over_the_factor(monkeypatch):
    """Rate: factors 0.1, 1, 10 (below the balance f* = 43): the error falls 10x per step, as P / (2 f)."""
    exact = frequencies(beam(32, "eliminate"))
    errors = []
    for f in (0.1, 1.0, 10.0):
        monkeypatch.setattr(constrain, "FIXED_FACTOR", f)
        system = beam(32, "penalty")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", AccuracyWarning)
            errors.append(1 - frequencies(system)[0] / exact[0])
        assert errors[-1] == pytest.approx(system.penalty_choice.P / f / 2, rel=0.05)
    assert errors[0] / errors[1] == pytest.approx(10, rel=0.05)
    assert errors[1] / errors[2] == pytest.approx(10, rel=0.05)


@pytest.mark.parametrize("N", [32, 128])
@pytest.mark.parametrize("factor", [1e-2, 1e6])  # too soft (penalty error), the paper's 1e6 (round-off ~1e-2)
def test_bad_penalty_warns(monkeypatch, N, factor):
    monkeypatch.setattr(constrain, "FIXED_FACTOR", factor)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        system = beam(N, "penalty")
        frequencies(system)
    choice = system.penalty_choice
    assert choice.predicted() > max(constrain.PENALTY_TARGET, 4 * choice.R)
    assert penalty_warnings(record)


def test_no_penalty_without_penalty_rows():
    assert beam(8, "eliminate").penalty == 0.0
    assert beam(8, "eliminate").penalty_choice is None


@pytest.mark.parametrize("N", [32, 128])
def test_a_posteriori_errors_of_every_mode(N):
    """sum_j alpha_j (C x_i)_j^2 / lambda_i from the computed shapes predicts each mode's error (first order)."""
    exact = frequencies(beam(N, "eliminate"))
    system = beam(N, "penalty")
    mats = system.linear()
    res = modes(mats["M"], mats["K"], count=5)
    predicted = system.penalty_errors(res.shapes, res.eigenvalues) / 2  # frequencies: half
    np.testing.assert_allclose(1 - res.frequencies / exact, predicted, rtol=0.05)
    assert np.all(beam(N, "eliminate").penalty_errors(np.eye(3)[:, :1], np.ones(1)) == 0)


@pytest.mark.parametrize("N", [32, 128])
def test_modes_analysis_warns_from_the_computed_modes(monkeypatch, N):
    """The modes analysis checks every mode it returns: silent by default, a warning for a too soft penalty."""
    from mechgen.analyses.modes import run_modes

    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        run_modes(beam(N, "penalty"), {"count": 5}, {})
    assert not penalty_warnings(record)
    monkeypatch.setattr(constrain, "FIXED_FACTOR", 1e-2)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        run_modes(beam(N, "penalty"), {"count": 5}, {})
    assert any("mode 5" in m for m in penalty_warnings(record))



@pytest.mark.parametrize("seed", range(8))
def test_lowest_modes_survive_unresolved_high_modes(seed):
    """A light dof spreads the spectrum as the beam's slope dofs do: K well scaled (random SPD, entries ~1),
    M = diag(1, 1, 1, 1e-20). The top mode's mu = 1/omega^2 ~ 1e-20 lies below the inverse solver's
    resolution (n eps max mu ~ 1e-15) and comes out of round-off with either sign; it must be kept as an
    unresolved high mode, not make the solver fall back to K phi = lambda M phi (whose error eps * 1e20
    swamps the low modes). Reference: the massless dof condensed out exactly (Schur complement
    K11 - K12 K22^-1 K21 with M11 = I), to which the low modes converge as the mass -> 0 (O(1e-20))."""
    import warnings

    a = np.random.default_rng(seed).standard_normal((4, 4))
    K = a @ a.T + 4 * np.eye(4)
    M = np.diag([1.0, 1.0, 1.0, 1e-20])
    condensed = K[:3, :3] - np.outer(K[:3, 3], K[3, :3]) / K[3, 3]
    exact = np.sqrt(np.linalg.eigvalsh(condensed))
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        res = modes(M, K)
    assert res.frequencies[:3] == pytest.approx(exact, rel=1e-10)
    assert res.frequencies[3] > 1e6
