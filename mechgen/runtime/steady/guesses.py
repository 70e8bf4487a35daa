"""Numerical starting guesses for steady states, and the shape measures they aim at (numpy only, no sympy).

A model declares which of these it uses (``Model.shape_output(name, fn, start=...)``) and maps its parameters
onto their arguments; the numbers are computed here.

* :func:`loop_count` - the loop label of a planar balloon-like curve sampled along its length;
* :func:`sine_loop_guesses` - balloon shapes with a given loop label: sine graphs of the right length,
  one per tension level.
"""
from __future__ import annotations

from typing import Iterator

import numpy as np


def loop_count(u) -> float:
    """The loop label of a planar balloon (Sarangi et al.: single 1, one-and-a-half 1.5, double 2 ...).

    ``u.x`` are the samples of x along the string from the fixed eyelet (x = 0) to the rotating one (x = 1),
    ``u.x_s`` its slopes. n_c = the sign changes of x between the eyelets; loops = 1 if n_c = 0, else n_c + 1
    when the last bulge is complete (x_s < 0 at the rotating eyelet, i.e. the tension vector's Q(l0) < 0: |x|
    peaked before the eyelet, since x(l0) = 1 > 0) and n_c + 1/2 otherwise (benchmarks/balloon_notes.md,
    section 4)."""
    x = np.asarray(u.x, float)[1:-1]
    signs = np.sign(x[x != 0.0])
    crossings = int(np.count_nonzero(signs[1:] != signs[:-1]))
    if crossings == 0:
        return 1.0
    return crossings + (1.0 if float(np.asarray(u.x_s)[-1]) < 0.0 else 0.5)


def sine_loop_guesses(value, s, *, height, length, domain, stiffness, tensions) -> Iterator[dict]:
    """Starting guesses for a balloon with ``value`` loops: n_c = round(value + 1/2) - 1 axis crossings.

    The string runs from the origin to (1, 0, ``height``); ``length`` is its undeformed length l0, ``s`` the
    sample positions on the domain [0, ``domain``] (sigma = s / domain along the material). Each guess is the
    graph x(z) = z/h + a sin(k pi z/h), k = n_c + 1 (the sign of a makes the last bulge positive), with a
    chosen (brentq) so that the curve's length is l0 lambda_g: a uniformly stretched string at the tension
    level p_g (lambda_g = 1 + p_g / ``stiffness``, the small-strain stretch), material points spaced evenly
    along it, and the tension vector n = p_g t along its tangent t. One guess per p_g in ``tensions``, in
    order: dicts with ``u``, ``u_s`` and ``n`` (field -> values at s), as ``Model.shape_output``'s ``start``
    gives them.
    """
    from scipy.integrate import cumulative_trapezoid
    from scipy.optimize import brentq

    k = max(int(np.floor(float(value) + 0.5)), 1)
    h, l0 = float(height), float(length)
    sigma = np.asarray(s, float) / float(domain)
    zeta = np.linspace(0.0, 1.0, 4001)
    cos = np.cos(k * np.pi * zeta)
    for tension in tensions:
        target = l0 * (1.0 + tension / float(stiffness))

        def excess(a):
            return h * np.trapezoid(np.sqrt(1.0 + ((1.0 + a * k * np.pi * cos) / h) ** 2), zeta) - target

        a = 0.0
        if excess(0.0) < 0.0:
            top = 1.0
            while excess(top) < 0.0:
                top *= 2.0
            a = brentq(excess, 0.0, top, xtol=1e-12)
        a *= (-1.0) ** (k - 1)
        slope = (1.0 + a * k * np.pi * cos) / h  # dx/dz
        arc = cumulative_trapezoid(h * np.sqrt(1.0 + slope**2), zeta, initial=0.0)
        at = arc / arc[-1]
        x = np.interp(sigma, at, zeta + a * np.sin(k * np.pi * zeta))
        z = np.interp(sigma, at, h * zeta)
        norm = np.sqrt(1.0 + slope**2)
        tx, tz = np.interp(sigma, at, slope / norm), np.interp(sigma, at, 1.0 / norm)
        stretch_ = arc[-1] / float(domain)
        zero = np.zeros_like(sigma)
        yield {"u": {"x": x, "y": zero, "z": z}, "u_s": {"x": stretch_ * tx, "y": zero, "z": stretch_ * tz},
               "n": {"x": tension * tx, "y": zero, "z": tension * tz}}
