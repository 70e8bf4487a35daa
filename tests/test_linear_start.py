"""periodic_orbit's start = "linear" (issue 27, item 2): a forced orbit's first guess from the linear forced response.

References, computed here:

* The receptance of m x'' + c x' + k x = F cos(w t): X = F / (k - m w^2 + i c w) (the linear guess's first harmonic,
  x = Re(X e^{i w t})).
* The forced Duffing orbit x'' + 0.1 x' + x + x^3 = 0.3 cos(w t) by a harmonic balance written here: 9 harmonics at
  64 phases, scipy.optimize.fsolve on the Fourier coefficients to xtol 1e-13.
"""
import math

import numpy as np
import pytest
from scipy.optimize import fsolve

import mechgen
from mechgen.analyses.linear_start import linear_coefficients
from mechgen.cli import main

C, K3, F = 0.1, 1.0, 0.3


def hand_hb(w: float, H: int = 9, N: int = 64) -> np.ndarray:
    """(a0, a_1..a_H, b_1..b_H) of x'' + C x' + x + K3 x^3 = F cos(w t) by harmonic balance (module doc)."""
    theta = 2 * math.pi * np.arange(N) / N
    k = np.arange(1, H + 1)
    c, s = np.cos(np.outer(theta, k)), np.sin(np.outer(theta, k))

    def residual(u):
        a0, a, b = u[0], u[1:H + 1], u[H + 1:]
        x = a0 + c @ a + s @ b
        xd = w * (-s @ (k * a) + c @ (k * b))
        xdd = -w**2 * (c @ (k**2 * a) + s @ (k**2 * b))
        r = xdd + C * xd + x + K3 * x**3 - F * np.cos(theta)
        return np.concatenate([[r.mean()], 2 * c.T @ r / N, 2 * s.T @ r / N])

    guess = np.zeros(2 * H + 1)
    guess[1] = F / (1 - w**2)
    return fsolve(residual, guess, xtol=1e-13)


def test_linear_guess_is_the_receptance():
    """The guess's first harmonic is F / (k - m w^2 + i c w) (to 1e-14: one 1 x 1 complex solve), its other
    harmonics zero (the forcing has none)."""
    system = mechgen.compile("duffing", backend="c").with_params(c=C, F=F, k3=K3, w=0.5)
    U = linear_coefficients(system, 0.5, 7)
    X = F / (1.0 - 0.25 + 1j * C * 0.5)
    assert U[1, 0] == pytest.approx(X.real, abs=1e-14) and U[8, 0] == pytest.approx(-X.imag, abs=1e-14)
    assert np.max(np.abs(np.delete(U[:, 0], [1, 8]))) < 1e-14


@pytest.mark.parametrize("method, tol", [
    ("harmonic_balance", 1e-13),  # the same 9 harmonics and phases: round-off (measured 3e-16)
    ("collocation", 1e-10),  # its mesh error and the hand series' truncation (measured 1.1e-11)
    ("shooting", 1e-10),  # DOP853 and the hand series' truncation (measured 1.1e-11)
])
def test_far_from_resonance_newton_converges_in_a_few_steps(method, tol):
    """At w = 0.5 (half the linear resonance: the cubic force is 13 % of the linear one) each method converges
    from the linear response in at most 4 Newton steps (measured 4; 5 from the zero guess), to the hand-written
    harmonic balance's orbit: its Fourier coefficients (mean, cos, sin of 9 harmonics)."""
    system = mechgen.compile("duffing", backend="c").with_params(c=C, F=F, k3=K3, w=0.5)
    r = mechgen.periodic_orbit(system, method=method, frequency=0.5, start="linear", harmonics=9)
    assert r["iterations"] <= 4
    u = hand_hb(0.5)
    h = r["harmonics"]["x"]
    found = np.concatenate([[h["mean"]], h["cos"], h["sin"]])
    assert np.max(np.abs(found - u)) < tol


def test_frequency_response_from_the_linear_start(tmp_path):
    """A scene whose forced orbit starts linear at w = 0.5 and is continued to w = 0.8: every point of the branch
    matches the hand-written harmonic balance at its w (the state at t = 0 to 1e-9: both 9 harmonics, the corrector's
    and fsolve's tolerances)."""
    path = tmp_path / "frc.toml"
    path.write_text(f'''model = "duffing"
backend = "c"
[params]
c = {C}
k3 = {K3}
F = {F}
w = 0.5
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "harmonic_balance"
harmonics = 9
frequency = "w"
start = "linear"
[[analysis]]
name = "frc"
kind = "continuation"
about = "orbit"
parameter = "w"
stop = 0.8
max_step = 0.1
''')
    analyses = mechgen.run(str(path))["analyses"]
    assert analyses[0]["outputs"]["iterations"] <= 4
    for point in analyses[1]["outputs"]["branch"]:
        u = hand_hb(point["w"])
        x, xd = point["start"]["x"], point["start"]["x_dot"]
        assert x == pytest.approx(u[0] + u[1:10].sum(), abs=1e-9)
        assert xd == pytest.approx(point["w"] * (np.arange(1, 10) * u[10:]).sum(), abs=1e-9)


def scene_text(extra: str, c: float = 0.0, w: float = 1.0) -> str:
    return f'''model = "duffing"
backend = "c"
[params]
c = {c}
F = 0.3
w = {w}
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "harmonic_balance"
{extra}
'''


@pytest.mark.parametrize("extra, where, words", [
    # undamped, at the linear resonance k - m w^2 = 0: the linear response does not exist
    # (found while running: the key is named without the analysis's position)
    ('frequency = "w"\nstart = "linear"', "key 'start'", ["singular", "resonance"]),
    ('frequency = "w"\nstart = "linear"\nq0 = { x = 1.0 }', "analysis[1].start", ["both"]),
    ('period = 6.0\nstart = "linear"\nq0 = { x = 1.0 }', "analysis[1].start", ["autonomous"]),
    ('frequency = "w"\nstart = "quadratic"', "analysis[1].start", ["linear"]),
])
def test_linear_start_refusals(tmp_path, capsys, extra, where, words):
    """Exit 2 naming the key: an undamped resonance, a second guess, an autonomous orbit, an unknown start."""
    path = tmp_path / "bad.toml"
    path.write_text(scene_text(extra))
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert where in err and all(w in err for w in words), err
