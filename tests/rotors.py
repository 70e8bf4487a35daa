"""Shared rotor builders for the spinning-shaft tests (one derivation serves them all)."""
from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

import numpy as np

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.runtime.fields.mesh import Layout
from mechgen.symbolic.specialize import specialize

STEEL = {"E_s": 211e9, "G_s": 81.2e9, "rho": 7810.0, "D": 0.05, "L": 1.0}


@lru_cache(maxsize=None)
def _compiled(bc: str, shear: str):
    """The shaft's linear kernels with every numeric parameter free (one derivation serves all tests)."""
    model = models.get("spinning_shaft")
    free = tuple(p.name for p in model.param_list if p.is_numeric)
    system, _ = compile_model(model, specialize(model, {"bc": bc, "shear": shear}, free=free), kernels={"linear"},
                              backend="numpy")
    return system


def shaft(values: dict, layout: Layout | None = None):
    """A shaft with these parameter values and choices (bc, shear, discretisation, N) and optional layout."""
    values = {**STEEL, **values}
    base = _compiled(values.get("bc", "free-free"), values.get("shear", "cowper"))
    model = models.get("spinning_shaft")
    params = np.array([float(values.get(n, model.param(n).default)) for n in base.meta["params"]])
    choices = {**base.choices, **{k: values[k] for k in ("discretisation", "N") if k in values}}
    return replace(base, params=params, choices=choices, layout=layout, _cache={})
