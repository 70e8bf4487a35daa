"""Impulse trains in modal coordinates and the windowed spectrum of the response (numerics only).

With mass-normalised modes phi_n (phi_n^T M phi_m = delta_nm, phi_n^T K phi_n = omega_n^2, rad/s)
and light modal damping zeta, each modal coordinate obeys

    q_n'' + 2 zeta omega_n q_n' + omega_n^2 q_n = sum_k P_nk delta(t - t_k),   P_nk = phi_n^T g_k

(g_k the generalized impulse of the k-th blow, N s per unit coordinate), so that, exactly,

    q_n(t) = sum_k P_nk h_n(t - t_k),   h_n(t) = exp(-zeta omega_n t) sin(omega_d t) / omega_d  (t >= 0),

omega_d = omega_n sqrt(1 - zeta^2). On an even grid t_j = j dt, h_n(tau + m dt) is a combination of
r^m cos(m theta) and r^m sin(m theta) (r = exp(-zeta omega_n dt), theta = omega_d dt), each the output
of a second-order recursion; an impulse between samples enters at the next sample with its exact phase,
so the sampled response is exact to round-off for any impulse times (scipy.signal.lfilter, O(samples)).
"""
from __future__ import annotations

import numpy as np


def mass_normalised(M, shapes: np.ndarray) -> np.ndarray:
    """The columns of ``shapes`` scaled so that phi^T M phi = 1."""
    Mphi = M @ shapes
    return shapes / np.sqrt(np.einsum("ij,ij->j", shapes, np.asarray(Mphi)))


def damped_sine(omega: float, zeta: float, t: np.ndarray) -> np.ndarray:
    """h(t) = exp(-zeta omega t) sin(omega_d t) / omega_d for t >= 0, 0 before (s, per unit impulse)."""
    wd = omega * np.sqrt(1.0 - zeta**2)
    t = np.asarray(t, float)
    return np.where(t >= 0, np.exp(-zeta * omega * np.maximum(t, 0)) * np.sin(wd * np.maximum(t, 0)) / wd, 0.0)


def modal_train(omega: float, zeta: float, dt: float, samples: int, times: np.ndarray,
                impulses: np.ndarray, derivative: int = 0) -> np.ndarray:
    """q(j dt) (``derivative`` 0) or q'(j dt) (1), j < samples, of one mode struck by ``impulses``
    (generalized, N s) at ``times`` (s, >= 0).

    Both responses are exp(-a s) (alpha cos(omega_d s) + beta sin(omega_d s)), s = t - t_k, a = zeta omega:
    h = (0, 1/omega_d), h' = (1, -a/omega_d).
    """
    from scipy.signal import lfilter

    a, wd = zeta * omega, omega * np.sqrt(1.0 - zeta**2)
    alpha, beta = (0.0, 1.0 / wd) if derivative == 0 else (1.0, -a / wd)
    r, theta = np.exp(-a * dt), wd * dt
    times = np.asarray(times, float)
    j = np.ceil(times / dt - 1e-12).astype(int)   # first sample at or after each blow
    keep = j < samples
    j, tau, p = j[keep], j[keep] * dt - times[keep], np.asarray(impulses, float)[keep]
    decay, cos, sin = p * np.exp(-a * tau), np.cos(wd * tau), np.sin(wd * tau)
    u = np.zeros(samples)          # coefficient of r^m cos(m theta), m samples after the blow's first
    w = np.zeros(samples)          # coefficient of r^m sin(m theta)
    np.add.at(u, j, decay * (alpha * cos + beta * sin))
    np.add.at(w, j, decay * (beta * cos - alpha * sin))
    den = [1.0, -2.0 * r * np.cos(theta), r * r]
    # impulse responses: (1 - r cos(theta) z^-1) / den -> r^m cos(m theta); r sin(theta) z^-1 / den -> r^m sin(m theta)
    return lfilter([1.0, -r * np.cos(theta)], den, u) + lfilter([0.0, r * np.sin(theta)], den, w)


def hann_spectrum(signal: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies (Hz) and amplitude |X_k| 2 / sum(w) of the Hann-windowed signal (a sine of amplitude A
    on a bin reads A)."""
    n = len(signal)
    window = np.hanning(n)
    x = np.fft.rfft((signal - np.mean(signal)) * window)
    return np.fft.rfftfreq(n, 1.0 / rate), np.abs(x) * 2.0 / np.sum(window)


def spectral_peaks(freq: np.ndarray, amp: np.ndarray, count: int, f_max: float, separation: int) -> list[float]:
    """The ``count`` most prominent local maxima of log amplitude below ``f_max`` (Hz), at least ``separation``
    bins apart (scipy.signal.find_peaks), ascending, each refined by the parabola through log amplitude at
    the bin and its neighbours (a shift of at most half a bin). Prominence in log amplitude weighs a
    resonance by its height above its surroundings, not by its level, which falls with frequency."""
    from scipy.signal import find_peaks

    level = np.log(np.maximum(amp, 1e-300 + np.max(amp) * 1e-15))
    found, props = find_peaks(level[freq <= f_max], distance=max(1, separation), prominence=0.0)
    top = found[np.argsort(props["prominences"])[::-1][:count]]
    df = freq[1] - freq[0]
    out = []
    for k in top:
        if 0 < k < len(level) - 1:
            lo, mid, hi = level[k - 1:k + 2]
            curve = lo - 2 * mid + hi
            shift = 0.5 * (lo - hi) / curve if curve < 0 else 0.0
        else:
            shift = 0.0
        out.append(float(freq[k] + np.clip(shift, -0.5, 0.5) * df))
    return sorted(out)
