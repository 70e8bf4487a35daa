"""What went wrong at a state where a solver failed: the failure path only, never per call.

DESIGN.md's rule: a kernel that produces NaN/Inf is named with its output and its input. The hot
path (prepared kernel calls in integrators and Newton) does not check every output; when a solver
sees a non-finite residual, tangent or rate, or a singular mass matrix, it calls these functions
once to say which:

* :func:`nonfinite_kernels` evaluates the system's kernels at the state without the finiteness
  check and names the first non-finite entry of each output: ``kernel 'residual' output r[2]
  (coordinate 'theta') = nan``, with the state and the free parameters' values;
* :func:`singular_mass` tests M = dr/da: singular when its smallest eigenvalue magnitude is at most
  n eps max|eig| (or M is zero), named by the coordinates the null vector moves (no inertia);
* :func:`explain_state` combines the two for a first-order state x = (q, v, z), and else names the
  largest rate |dx_i/dt| (a finite but huge acceleration: a mass near zero, a stiff force).
"""
from __future__ import annotations

import numpy as np

#: state ports the kernels take, in the order they are shown
STATE_PORTS = ("q", "v", "a", "z", "t")
#: at most this many entries of a vector are shown
SHOWN = 6


def _show_vector(values, names=None) -> str:
    arr = np.atleast_1d(np.asarray(values, float)).ravel()
    if names is not None and len(names) == arr.size:
        items = [f"{n}: {v:.6g}" for n, v in zip(names[:SHOWN], arr[:SHOWN])]
        text = "{" + ", ".join(items)
    else:
        text = "[" + ", ".join(f"{v:.6g}" for v in arr[:SHOWN])
    more = f", ... ({arr.size} in all)" if arr.size > SHOWN else ""
    return text + more + ("}" if names is not None and len(names) == arr.size else "]")


def _entry(name: str, value, index: int, shape, coordinates) -> str:
    """``r[2] (coordinate 'theta')`` or ``r_a[1, 2] (row 'r', column 'theta')``."""
    n = len(coordinates) if coordinates is not None else -1
    if shape is not None and len(shape) == 2:
        i, j = divmod(int(index), int(shape[1]))
        where = f"{name}[{i}, {j}]"
        if shape[0] == n and shape[1] == n:
            where += f" (row '{coordinates[i]}', column '{coordinates[j]}')"
        return where
    where = f"{name}[{index}]"
    if n > 0 and np.size(value) == n:
        where += f" (coordinate '{coordinates[index]}')"
    return where


def nonfinite_kernels(system, state: dict, kernels=("residual", "tangent", "rates")) -> str:
    """The first non-finite entry of each output of ``kernels`` at ``state`` (a System's kernels), with the
    inputs; "" when every output is finite (or the system has no such kernels)."""
    names = list(getattr(system, "coordinates", []) or [])
    found = []
    for kernel in kernels:
        if kernel not in getattr(system, "kernels", {}) or not hasattr(system, "call"):
            continue
        try:
            out = system.call(kernel, check=False, **state)
        except Exception:  # the diagnosis never hides the error it explains
            continue
        for port, value in out.items():
            dense = value.toarray() if hasattr(value, "toarray") else np.asarray(value, float)
            bad = np.flatnonzero(~np.isfinite(dense.ravel()))
            if bad.size:
                k = int(bad[0])
                shape = dense.shape if dense.ndim == 2 else None
                if kernel == "rates":  # dz/dt: one entry per internal variable
                    internal = list(getattr(getattr(system, "metadata", None), "internal", ()) or ())
                    dense, shape = dense.ravel(), None
                    where = f"{port}[{k}]" + (f" (internal variable '{internal[k]}')" if k < len(internal) else "")
                else:
                    where = _entry(port, dense, k, shape, names)
                found.append(f"kernel '{kernel}' output {where} = "
                             f"{dense.ravel()[k]}" + (f" ({bad.size} entries non-finite)" if bad.size > 1 else ""))
    if not found:
        return ""
    return "; ".join(found) + " at inputs " + inputs_text(system, state)


def inputs_text(system, state: dict) -> str:
    """The state (q by coordinate, v, z, t) and the free parameters' values, for a message."""
    names = list(getattr(system, "coordinates", []) or [])
    parts = []
    for port in STATE_PORTS:
        if state.get(port) is not None:
            value = state[port]
            parts.append(f"{port} = " + (f"{float(value):.6g}" if np.ndim(value) == 0 else
                                         _show_vector(value, names if port in ("q", "v", "a") else None)))
    params = getattr(getattr(system, "metadata", None), "params", ())
    if len(params):
        parts.append("parameters " + _show_vector(system.params, list(params)))
    return ", ".join(parts)


def singular_mass(M, coordinates=None) -> str:
    """"" when M is regular, else which coordinates have no inertia (the null vector's largest components).

    Singular: the smallest |eigenvalue| of the symmetric part is at most n eps max|eigenvalue|.
    """
    dense = M.toarray() if hasattr(M, "toarray") else np.atleast_2d(np.asarray(M, float))
    n = dense.shape[0]
    if n == 0 or n > 4000 or not np.all(np.isfinite(dense)):
        return ""
    w, V = np.linalg.eigh(0.5 * (dense + dense.T))
    scale = float(np.max(np.abs(w)))
    k = int(np.argmin(np.abs(w)))
    if scale > 0 and abs(w[k]) > n * np.finfo(float).eps * scale:
        return ""
    null = np.abs(V[:, k])
    moved = [int(i) for i in np.flatnonzero(null >= 0.5 * null.max())]
    names = list(coordinates) if coordinates is not None and len(coordinates) == n else None
    which = ", ".join(f"'{names[i]}'" if names else f"{i}" for i in moved[:SHOWN])
    what = "is zero" if scale == 0 else f"is singular (eigenvalue {w[k]:.3g} against the largest {scale:.3g})"
    return (f"the mass matrix M = dr/da {what}: no inertia along coordinate{'s' if len(moved) > 1 else ''} "
            f"{which} (a mass or inertia parameter of 0?)")


def explain_state(system, t: float, x) -> str:
    """Why dx/dt = (v, -M^-1 r, g) fails or explodes at the first-order state x: a non-finite kernel output,
    a singular mass matrix, or else the largest rate."""
    n, m = int(system.n), int(getattr(system, "m", 0) or 0)
    x = np.asarray(x, float)
    q, v, z = x[:n], x[n:2 * n], (x[2 * n:] if m else None)
    state = {"q": q, "v": v, "z": z, "t": t}
    if not np.all(np.isfinite(x)):
        return "the state itself is not finite: " + inputs_text(system, state)
    kernels = nonfinite_kernels(system, state)
    if kernels:
        return kernels
    try:
        M = system.tangent(q, v, None, z, t)["r_a"]
    except Exception:  # the diagnosis never hides the error it explains
        return ""
    singular = singular_mass(M, getattr(system, "coordinates", None))
    if singular:
        return singular + " at " + inputs_text(system, {"q": q, "t": t})
    try:
        rates = np.asarray(system.rhs(t, x), float)
    except Exception:  # the diagnosis never hides the error it explains
        return ""
    names = list(getattr(system, "coordinates", []) or [])
    labels = ([f"d{c}/dt" for c in names] + [f"d({c}_dot)/dt" for c in names] if len(names) == n else
              [f"dx[{i}]/dt" for i in range(2 * n)])
    internal = list(getattr(getattr(system, "metadata", None), "internal", ()) or ())
    labels += [f"d{c}/dt" for c in internal] if len(internal) == m else [f"dz[{i}]/dt" for i in range(m)]
    i = int(np.argmax(np.abs(rates)))
    diag = np.abs(M.diagonal() if hasattr(M, "diagonal") else np.diag(M))
    span = (f" (the mass matrix's diagonal spans {diag.min():.3g} to {diag.max():.3g})" if diag.size else
            " (no coordinates: internal variables only)")
    return f"the fastest rate there is {labels[i]} = {rates[i]:.3g}{span} at " + inputs_text(system, state)
