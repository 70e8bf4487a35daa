"""A compiled system's parameter values by name, and a system with other values of its free ones."""
from __future__ import annotations

from mechgen import models
from mechgen.errors import SceneError


def model_of(system):
    """The system's Model, by its canonical reference (``meta["source"]``, set by the pipeline); imports it."""
    return models.get(system.metadata.reference)


def info_of(system):
    """The system's model facts (mechgen.scene.info.ModelInfo), from the caches: no import of the model."""
    from mechgen.scene.info import model_info

    return model_info(system.metadata.reference)


def parameter_dict(system, p) -> dict:
    """Numeric parameter values: the model's defaults, the scene's fixed ones, the free ones from p."""
    info = info_of(system)
    values = {name: float(prm.default) for name, prm in info.params.items() if prm.numeric}
    values.update({k: float(v) for k, v in getattr(system, "fixed", {}).items()})
    values.update(zip(system.metadata.params, (float(v) for v in p)))
    return values


def with_free_params(system, values: dict, key: str = "params"):
    """A new system with some free parameters set (``steady``'s ``params``, a sweep's point);
    the system given is left as it was."""
    names = list(system.metadata.params)
    for name in values:
        if name not in names:
            raise SceneError(f"parameter {name!r} is not free in the compiled kernels", key=f"{key}.{name}",
                             expected="a parameter the scene leaves free: " + ", ".join(names))
    return system.with_params(**{name: float(value) for name, value in values.items()})
