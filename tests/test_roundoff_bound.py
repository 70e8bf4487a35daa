"""The round-off bound of a continuum's eigenvalues (issue 33): refining a beam past a few thousand elements loses
accuracy, since each assembled entry of K carries a relative rounding eps while the lowest mode's phi^T K phi cancels
to a value (N/pi)^4 times smaller than |phi|^T |K| |phi|. ``modes`` and ``stability`` report the first-order bound
on the lowest frequency's relative error (``roundoff_bound``, mechgen.runtime.linear.modes.roundoff_bound) and
refuse the run at params.N when it exceeds ``roundoff_rtol`` (default 1e-2).

References: the Euler-Bernoulli beam's closed forms, omega_n = (beta_n L)^2 sqrt(EI / (rhoA L^4)) with
beta_1 L = pi (pinned-pinned) and 1.8751040687119611 (clamped-free, the root of cos x cosh x = -1); Beck's
frequency equation (tests/test_field_nonconservative.py). The Hermite elements' own error, (k h)^4 / 1440 on
omega (k = beta_1 / L), is below 1e-9 at the sizes used here.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import mechgen
from mechgen.errors import InputError
from test_field_nonconservative import beck_roots, column

CANTILEVER = brentq(lambda x: np.cos(x) * np.cosh(x) + 1.0, 1.5, 2.5)  # beta_1 L = 1.8751...


def beam(N: int, bc: str = "clamped-free"):
    return mechgen.compile("euler_bernoulli_beam", {"EI": 1.0, "rhoA": 1.0, "L": 1.0, "bc": bc,
                                                    "discretisation": "hermite", "N": N}, backend="c",
                           kernels=["linear", "residual"])


def discretisation_error(beta: float, N: int) -> float:
    """The Hermite cubic's relative error on omega_1 to leading order, (beta h)^4 / 1440 (h = L / N)."""
    return (beta / N) ** 4 / 1440


@pytest.mark.parametrize("bc, beta", [("clamped-free", CANTILEVER), ("pinned-pinned", np.pi)])
@pytest.mark.parametrize("N", [250, 1000])
def test_below_the_bound_the_lowest_frequency_is_accurate_to_it(bc, beta, N):
    """Below roundoff_rtol the run goes on and the reported bound holds: |omega_1 / exact - 1| is within
    roundoff_bound (plus the elements' own error). Measured: errors 0.002-0.04 of the bound."""
    out = mechgen.modes(beam(N, bc), count=3).outputs
    exact = beta**2
    error = abs(out["frequencies"][0] / exact - 1)
    assert out["roundoff_bound"] < 1e-2
    assert error <= out["roundoff_bound"] + discretisation_error(beta, N), (error, out["roundoff_bound"])


def test_above_the_bound_the_run_is_refused_at_N():
    """N = 4000 Hermite elements of a cantilever: the bound on omega_1 is about 0.1 (eps N^4 grown), above the
    default roundoff_rtol = 1e-2: InputError at params.N stating the bound. With roundoff_rtol = 1 it runs, and the
    bound still holds (measured error 9e-3, bound 0.11): the refusal is about accuracy, not a failure."""
    with pytest.raises(InputError) as info:
        mechgen.modes(beam(4000), count=3)
    assert info.value.key == "params.N" and "bounds the lowest frequency's relative error by" in str(info.value)
    bound = float(str(info.value).split("relative error by ")[1].split()[0])
    assert bound > 1e-2
    out = mechgen.modes(beam(4000), count=3, roundoff_rtol=1.0).outputs
    assert out["roundoff_bound"] == pytest.approx(bound, rel=1e-1)  # the same bound, printed to 2 digits
    assert abs(out["frequencies"][0] / CANTILEVER**2 - 1) <= out["roundoff_bound"]


def test_a_tighter_tolerance_refuses_a_smaller_N():
    """roundoff_rtol = 1e-8 at N = 1000 (bound about 4e-4): refused; the key is the size that sets the bound."""
    with pytest.raises(InputError) as info:
        mechgen.modes(beam(1000), count=3, roundoff_rtol=1e-8)
    assert info.value.key == "params.N" and "roundoff_rtol = 1e-08" in str(info.value)


def test_beck_column_stability_is_refused_where_round_off_takes_over():
    """Beck's column, P = 10: at N = 1000 (no refinement) the three lowest frequencies match the frequency equation
    within the bound; at N = 4000 (measured 4.3e-3 off, still 'stable') the bound, about 0.05, is refused; at N = 2000
    with the default refinement the check at 2N = 4000 is what is refused."""
    exact = np.array(beck_roots(10.0, 60.0)[:3])
    out = mechgen.stability(column(10.0, N=1000), count=3, refine=False).outputs
    assert np.all(np.abs(np.array(out["frequencies"][:3]) / exact - 1) <= out["roundoff_bound"])
    with pytest.raises(InputError) as info:
        mechgen.stability(column(10.0, N=4000), count=3, refine=False)
    assert info.value.key == "params.N", info.value
    with pytest.raises(InputError) as info:
        mechgen.stability(column(10.0, N=2000), count=3)
    assert info.value.key == "params.N" and "check at 2N = 4000" in str(info.value), info.value


def test_the_shipped_beam_scene_reports_a_tiny_bound(capsys):
    """scenes/beam_modes.toml (quintic, N = 16) runs and reports roundoff_bound far below the tolerance."""
    from pathlib import Path

    result = mechgen.run(str(Path(__file__).resolve().parent.parent / "scenes" / "beam_modes.toml"))
    modes = next(a for a in result["analyses"] if a["kind"] == "modes")
    outputs = modes.get("outputs", modes)
    assert 0 < outputs["roundoff_bound"] < 1e-8
