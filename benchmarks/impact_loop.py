"""One compliant impact, three ways: mechgen's Python event loop, its compiled C loop, and a hand-written
``scipy.integrate.solve_ivp(..., method="DOP853", events=...)`` of the same contact law (no code generation).

The impact (mechgen/models/viscoelastic_impact.py; Butcher & Segalman 2000): a unit mass meets a unit
stiffness at x = 0 with speed 1 and stays in contact until the law's release guard falls through zero;
e = -v at release. The hand-written right-hand sides in contact (omega_n = 1, c = 2 zeta):

    kelvin_voigt, modified_kelvin_voigt:  x'' = -(x + 2 zeta x'),  release at x = 0 (KV) or F = 0 (MKV)
    maxwell:                              x'' = -(x - y),  y' = 2 zeta (x - y),  release at F = x - y = 0
    standard_linear (eps = 0.1):          x'' = -k1 (x - y),  y' = (k1 (x - y) - k2 y) / c,  release at F = 0,
                                          k1 = 1/eps, k2 = 1/(1 - eps), c = 2 zeta / (1 - eps)
    hunt_crossley (n = 1.5):              x'' = -|x|^n sgn(x) (1 + alpha x'),  alpha = 3 pi zeta / 2,  release at x = 0

All at rtol 1e-10, atol 1e-12 (the impact analysis's defaults), zeta = 0.3; the Python and C loops run
``integrate_hybrid`` exactly as the impact analysis does (stop after leaving contact). Each time is the
best of ``--repeat`` runs of ``--count`` impacts, per impact. Run:

    python benchmarks/impact_loop.py [--count 200] [--repeat 5]
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.integrate import solve_ivp

LAWS = ("kelvin_voigt", "modified_kelvin_voigt", "maxwell", "standard_linear", "hunt_crossley")
ZETA, EPS, N_HC = 0.3, 0.1, 1.5
RTOL, ATOL, T_END = 1e-10, 1e-12, 60.0


def handwritten(law: str, zeta: float):
    """(rhs, release event, x0) of the contact phase, written by hand."""
    if law in ("kelvin_voigt", "modified_kelvin_voigt"):
        def rhs(t, s):
            return [s[1], -(s[0] + 2 * zeta * s[1])]

        def release(t, s):
            return s[0] if law == "kelvin_voigt" else s[0] + 2 * zeta * s[1]
        x0 = [0.0, 1.0]
    elif law == "maxwell":
        def rhs(t, s):
            return [s[1], -(s[0] - s[2]), 2 * zeta * (s[0] - s[2])]

        def release(t, s):
            return s[0] - s[2]
        x0 = [0.0, 1.0, 0.0]
    elif law == "standard_linear":
        k1, k2, c = 1 / EPS, 1 / (1 - EPS), 2 * zeta / (1 - EPS)

        def rhs(t, s):
            return [s[1], -k1 * (s[0] - s[2]), (k1 * (s[0] - s[2]) - k2 * s[2]) / c]

        def release(t, s):
            return k1 * (s[0] - s[2])
        x0 = [0.0, 1.0, 0.0]
    else:
        alpha = 3 * np.pi * zeta / 2

        def rhs(t, s):
            return [s[1], -abs(s[0]) ** N_HC * np.sign(s[0]) * (1 + alpha * s[1])]

        def release(t, s):
            return s[0]
        x0 = [0.0, 1.0]
    release.terminal, release.direction = True, -1
    return rhs, release, x0


def exact(law: str, zeta: float) -> float:
    """e in closed form (Butcher & Segalman eqs. 4, 10-11, 16; Hunt-Crossley's implicit relation), or for the
    standard linear solid from the matrix exponential of its linear contact phase."""
    import math

    from scipy.linalg import expm
    from scipy.optimize import brentq

    if law in ("kelvin_voigt", "maxwell"):
        return math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    if law == "modified_kelvin_voigt":
        b = math.sqrt(1 - zeta**2)
        return math.exp(-(zeta / b) * math.atan2(2 * zeta * b, 2 * zeta**2 - 1))
    if law == "hunt_crossley":
        a = 1.5 * math.pi * zeta
        return brentq(lambda e: math.log((1 + a) / (1 - a * e)) - a * (1 + e), 1e-14, min(1, 1 / a) * (1 - 1e-15),
                      xtol=1e-16)
    k1, k2, c = 1 / EPS, 1 / (1 - EPS), 2 * zeta / (1 - EPS)
    A = np.array([[0, 1, 0], [-k1, 0, k1], [k1 / c, 0, -(k1 + k2) / c]])
    s0 = np.array([0.0, 1.0, 0.0])
    force = lambda t: (expm(A * t) @ s0) @ [k1, 0, -k1]  # noqa: E731
    grid = np.linspace(1e-6, 10, 2001)
    i = next(i for i in range(len(grid) - 1) if force(grid[i]) > 0 >= force(grid[i + 1]))
    return -(expm(A * brentq(force, grid[i], grid[i + 1], xtol=1e-16)) @ s0)[1]


def scipy_impact(law: str, zeta: float) -> float:
    rhs, release, x0 = handwritten(law, zeta)
    sol = solve_ivp(rhs, (0.0, T_END), x0, method="DOP853", rtol=RTOL, atol=ATOL, events=release)
    return -sol.y_events[0][0][1]


def mechgen_impact(system, loop: str) -> float:
    from mechgen.runtime.integration.events import integrate_hybrid

    x0 = np.array([0.0, 1.0, 0.0])
    tr = integrate_hybrid(system, x0, T_END, method="DOP853", rtol=RTOL, atol=ATOL, loop=loop,
                          stop_after=lambda e: e.source == 1)
    leave = next(e for e in tr.events if e.source == 1)
    return -leave.x_before[1]


def best(fn, count: int, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(count):
            fn()
        times.append((time.perf_counter() - t0) / count)
    return min(times)


def main() -> None:
    from mechgen.models.viscoelastic_impact import model
    from mechgen.pipeline import compile_model
    from mechgen.symbolic.specialize import specialize

    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(f"per impact (best of {args.repeat} x {args.count}), zeta = {ZETA}, rtol = {RTOL:g}, DOP853")
    print(f"{'law':22s} {'python loop':>12s} {'C loop':>10s} {'solve_ivp':>10s} {'py/C':>7s} {'ivp/C':>7s}"
          "   e exact          err C    err py   err ivp")
    for law in LAWS:
        system, _ = compile_model(model, specialize(model, {"law": law}, free=["zeta"]), backend="c")
        system = system.with_params(zeta=ZETA)
        e_c, e_py, e_ivp = mechgen_impact(system, "c"), mechgen_impact(system, "python"), scipy_impact(law, ZETA)
        e_ref = exact(law, ZETA)
        t_py = best(lambda: mechgen_impact(system, "python"), max(1, args.count // 10), args.repeat)
        t_c = best(lambda: mechgen_impact(system, "c"), args.count, args.repeat)
        t_ivp = best(lambda: scipy_impact(law, ZETA), max(1, args.count // 10), args.repeat)
        print(f"{law:22s} {t_py * 1e3:9.2f} ms {t_c * 1e3:7.3f} ms {t_ivp * 1e3:7.2f} ms {t_py / t_c:6.0f}x "
              f"{t_ivp / t_c:6.1f}x   {e_ref:.13f}  {abs(e_c - e_ref) / e_ref:.1e}  {abs(e_py - e_ref) / e_ref:.1e}  "
              f"{abs(e_ivp - e_ref) / e_ref:.1e}")


if __name__ == "__main__":
    main()
