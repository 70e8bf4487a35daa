"""A continuum's steady state as a boundary value problem in s: what ``steady`` and ``continuation`` report.

``bvp_summary``: every model output at the ends and its extremes along s (``tension_start``,
``radius_max`` ...) and the fields' slopes at the ends (``x_s_start`` ...), aliased. Shape outputs
(``Model.shape_output``: the balloon's ``loops``) are numbers measured on the sampled state
(``shape_values``). ``stability_about`` is the verdict of the Galerkin linearisation about one
state (mechgen.runtime.steady.branch_stability).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses.parameters import info_of, model_of, parameter_dict
from mechgen.runtime.steady.branch_stability import stability_along

SAMPLES = 201
SHAPE_SAMPLES = 1001


def bvp_summary(bvp, result, aliases: dict) -> dict:
    """Outputs at the ends and their extremes along s (sampled at SAMPLES points), aliased."""
    s = np.linspace(0.0, bvp.length_of(result), SAMPLES)
    out = {}
    for name, values in bvp.outputs(result, s).items():
        if name in ("potential_density", "hamiltonian"):
            continue
        out.update({f"{name}_start": float(values[0]), f"{name}_end": float(values[-1]),
                    f"{name}_max": float(values.max()), f"{name}_min": float(values.min())})
    ends = bvp.values(result, np.array([s[0], s[-1]]))
    for i, f in enumerate(bvp.fields):
        out[f"{f}_s_start"], out[f"{f}_s_end"] = float(ends[bvp.n + i, 0]), float(ends[bvp.n + i, 1])
    for alias, target in aliases.items():
        if target in out:
            out[alias] = out[target]
    return out


def reported(verdict) -> dict:
    """Verdict, lowest ten frequencies and eigenvalues of a StabilityResult, as the scene reports them."""
    return {"verdict": verdict.verdict, "frequencies": [float(f) for f in verdict.frequencies[:10]],
            "eigenvalues": [[float(e.real), float(e.imag)] for e in verdict.eigenvalues]}


def stability_about(system, bvp, result) -> dict:
    """The Galerkin linearisation's stability about one steady state (mechgen.runtime.steady.branch_stability)."""
    return reported(stability_along(system, bvp, None, [result])[0])


def stability_of_each(system, bvp, results) -> list[dict]:
    """The stability of every steady state in ``results`` (one Galerkin eigenproblem each); the one place to
    swap for a batched runtime call."""
    return [reported(v) for v in stability_along(system, bvp, None, results)]


def shape_declarations(system) -> tuple:
    """The model's shape outputs (Model.shape_output)."""
    if not info_of(system).shape_outputs:
        return ()
    return tuple(getattr(model_of(system), "shape_outputs", ()))


def parameter_namespace(system, p):
    """The parameter values as a model's declared functions read them (``p.lambda0``)."""
    from mechgen.symbolic.params import Namespace  # declared model code reads the model's own types

    return Namespace(parameter_dict(system, p))


def shape_values(system, bvp, result) -> dict:
    """Every shape output of the model on a steady state (sampled at SHAPE_SAMPLES points)."""
    declared = shape_declarations(system)
    if not declared:
        return {}
    s = np.linspace(0.0, bvp.length_of(result), SHAPE_SAMPLES)
    y = bvp.values(result, s)
    from mechgen.symbolic.declared import call_declared
    from mechgen.symbolic.params import Namespace

    u = Namespace({**{f: y[i] for i, f in enumerate(bvp.fields)},
                   **{f"{f}_s": y[bvp.n + i] for i, f in enumerate(bvp.fields)}})
    out = Namespace(bvp.outputs(result, s))
    p = parameter_namespace(system, result.p)
    return {d.name: float(call_declared(d.fn, s=s, u=u, out=out, p=p)) for d in declared}
