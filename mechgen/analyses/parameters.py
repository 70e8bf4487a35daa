"""A compiled system's parameter values by name, and a system with other values of its free ones."""
from __future__ import annotations

from mechgen import models
from mechgen.errors import SceneError


def model_of(system):
    """The system's Model, by its canonical reference (``meta["source"]``, set where scenes compile)."""
    return models.get(system.meta.get("source") or system.meta["model"])


def parameter_dict(system, p) -> dict:
    """Numeric parameter values: the model's defaults, the scene's fixed ones, the free ones from p."""
    model = model_of(system)
    values = {prm.name: float(prm.default) for prm in model.param_list if prm.is_numeric}
    values.update({k: float(v) for k, v in getattr(system, "fixed", {}).items()})
    values.update(zip(system.meta.get("params", []), (float(v) for v in p)))
    return values


def with_free_params(system, values: dict, key: str = "params"):
    """A new system with some free parameters set (``steady``'s ``params``, a sweep's point);
    the system given is left as it was."""
    names = list(system.meta.get("params", []))
    for name in values:
        if name not in names:
            raise SceneError(f"parameter {name!r} is not free in the compiled kernels", key=f"{key}.{name}",
                             expected="a parameter the scene leaves free: " + ", ".join(names))
    return system.with_params(**{name: float(value) for name, value in values.items()})
