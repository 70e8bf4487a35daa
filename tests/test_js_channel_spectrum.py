"""Spectra of the Johnson-Segalman channel linearised about its classical steady state (issue 28 item 4).

References: for xi = 0 (Oldroyd-B in shear) the velocity and shear-stress disturbances u = a sin-type modes
phi_n (phi'' = -kappa^2 phi, kappa = n pi / 2, phi(+-1) = 0) and tau_xy = b phi_n' decouple from the normal
stresses, and Re lambda^2 + (Re + epsilon kappa^2) lambda + kappa^2 (1 + epsilon) = 0 (worked out in the test's
docstring below); the essential spectrum is then {-1, -(1 + epsilon)/epsilon}. For xi = 0.2 an independent
second-order finite-difference discretisation on a uniform grid, with the linearised law written out by hand.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sl

from mechgen.errors import InputError
from mechgen.runtime.fluids import johnson_segalman as js
from mechgen.scene.run import run_scene

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "js_channel.toml"


def run(tmp_path, **values):
    text = SCENE.read_text()
    for key, value in values.items():
        lines = [f"{key} = {value}" if line.startswith(f"{key} = ") else line for line in text.splitlines()]
        text = "\n".join(lines) + "\n"
    scene = tmp_path / "channel.toml"
    scene.write_text(text)
    return {a["name"]: a["outputs"] for a in run_scene(str(scene))["analyses"]}


def test_oldroyd_b_limit_closed_form(tmp_path):
    """xi = 0: u = a phi_n, tau_xy = b phi_n' give Re lambda a = -eps kappa^2 a - kappa^2 b and lambda b = -b + a
    (the normal stresses feed back only triangularly), so Re lambda^2 + (Re + eps kappa^2) lambda + kappa^2 (1 + eps)
    = 0, for n = 1..4; the band is {-1, -1 - 1/eps} (J_T's tau_xy entry -1 - 1/eps)."""
    eps, Re = 0.06, 1.0
    out = run(tmp_path, xi=0.0, epsilon=eps, Re=Re)["spectrum"]
    found = np.array([complex(*v) for v in out["eigenvalues"]])
    for n in range(1, 5):
        k2 = (n * np.pi / 2) ** 2
        for root in np.roots([Re, Re + eps * k2, k2 * (1 + eps)]):
            assert np.min(np.abs(found - root)) < 1e-8  # collocation converges spectrally: 1e-12 at N = 72
    ends = np.array([complex(*v) for end in out["essential_spectrum"] for v in end])
    assert np.allclose(np.sort(ends.real), [-1 - 1 / eps] * 2 + [-1.0] * 4, atol=1e-12) and np.all(ends.imag == 0)


def _fd_eigenvalues(n, eps, xi, Re, G):
    """Second-order finite differences: u at interior nodes, stresses at all nodes of a uniform grid."""
    y = np.linspace(-1, 1, n + 1)
    h = y[1] - y[0]
    g = np.array([-np.sign(v) * js.classical_rate(G * abs(v), eps, xi) for v in y])
    S = g / (1 + xi * (2 - xi) * g**2)
    A, B = (2 - xi) * g * S, -xi * g * S
    Du = np.zeros((n + 1, n - 1))  # u' at every node from interior u (u = 0 at the walls), second order
    for i in range(n + 1):
        if 0 < i < n:
            stencil = ((i - 1, -0.5), (i + 1, 0.5))
        else:  # one-sided (-3 u_0 + 4 u_1 - u_2) / (2 h) with u_0 = 0, mirrored at the other wall
            stencil = ((1, 2.0), (2, -0.5)) if i == 0 else ((n - 1, -2.0), (n - 2, 0.5))
        for j, w in stencil:
            if 1 <= j <= n - 1:
                Du[i, j - 1] += w / h
    Dsy = np.zeros((n - 1, n + 1))
    D2 = np.zeros((n - 1, n - 1))
    for i in range(1, n):
        Dsy[i - 1, i - 1], Dsy[i - 1, i + 1] = -0.5 / h, 0.5 / h
        D2[i - 1, i - 1] = -2 / h**2
        if i > 1:
            D2[i - 1, i - 2] = 1 / h**2
        if i < n - 1:
            D2[i - 1, i] = 1 / h**2
    I, Z = np.eye(n + 1), np.zeros((n + 1, n + 1))
    d = np.diag
    rows = [
        [eps * D2, np.zeros((n - 1, n + 1)), np.zeros((n - 1, n + 1)), Dsy],
        [d((2 - xi) * S) @ Du, -I, Z, d((2 - xi) * g)],
        [d(-xi * S) @ Du, Z, -I, d(-xi * g)],
        [d(1 - xi / 2 * A + (2 - xi) / 2 * B) @ Du, d(-xi / 2 * g), d((2 - xi) / 2 * g), -I],
    ]
    L = np.block(rows)
    M = np.eye(L.shape[0])
    M[:n - 1, :n - 1] *= Re
    lam = sl.eigvals(L, M)
    return lam[np.isfinite(lam)]


def test_against_finite_differences(tmp_path):
    """xi = 0.2, G = 0.5, Re = 1: the rightmost point eigenvalues agree with a hand-written second-order
    finite-difference discretisation (measured 1.6e-4 at n = 100, 3.9e-5 at n = 200: O(h^2)) to 1e-3."""
    out = run(tmp_path)["spectrum"]
    fd = _fd_eigenvalues(200, 0.06, 0.2, 1.0, 0.5)
    for v in out["eigenvalues"][:4]:
        lam = complex(*v)
        assert np.min(np.abs(fd - lam)) < 1e-3 * abs(lam)
    assert out["verdict"] == "stable" and out["base_residual"] < 1e-14


def test_above_spurt_refused(tmp_path):
    with pytest.raises(InputError, match="spurt gradient"):
        run(tmp_path, G=1.0)


def test_stress_diffusion_closed_form(tmp_path):
    """xi = 0 with a stress diffusion D tau'' (tau' = 0 at the walls): tau_xy = b phi_n' still fits the Neumann
    condition, so Re lambda^2 + (Re (1 + D kappa^2) + eps kappa^2) lambda + eps kappa^2 (1 + D kappa^2) + kappa^2 = 0,
    n = 1..4; the normal stresses' Neumann modes give -1 - D (m pi / 2)^2. Every resolved eigenvalue is a point
    eigenvalue (the band is no longer essential)."""
    eps, Re, D = 0.06, 1.0, 0.01
    text = SCENE.read_text().replace("xi = 0.2", "xi = 0.0")
    scene = tmp_path / "diffusive.toml"
    scene.write_text(text + "stress_diffusion = 0.01\ncount = 60\n")
    out = {a["name"]: a["outputs"] for a in run_scene(str(scene))["analyses"]}["spectrum"]
    found = np.array([complex(*v) for v in out["eigenvalues"]])
    for n in range(1, 5):
        k2 = (n * np.pi / 2) ** 2
        for root in np.roots([Re, Re * (1 + D * k2) + eps * k2, eps * k2 * (1 + D * k2) + k2]):
            assert np.min(np.abs(found - root)) < 1e-8  # spectral convergence, as without diffusion
    for m in range(0, 5):
        assert np.min(np.abs(found - (-1 - D * (m * np.pi / 2) ** 2))) < 1e-8
    assert out["band_eigenvalues"] == 0
