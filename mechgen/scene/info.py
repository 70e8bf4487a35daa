"""Model facts the scene loader validates against (names only, nothing symbolic)."""
from __future__ import annotations

from dataclasses import dataclass

from mechgen import models
from mechgen.errors import InputError


@dataclass(frozen=True)
class ParamInfo:
    """What a scene may set for one parameter."""

    default: float | str
    choices: tuple[str, ...] | None
    integer: bool
    below: float | None = None


@dataclass(frozen=True)
class ModelInfo:
    """Names of a model's parameters, coordinates and outputs."""

    name: str
    params: dict
    coordinates: tuple[str, ...]
    outputs: tuple[str, ...]
    continuum: bool = False
    length: str | None = None
    parts: dict | None = None
    stress_form: bool = False
    fields: tuple[str, ...] = ()
    shape_outputs: tuple[str, ...] = ()
    #: the canonical reference of the model (mechgen.models.resolve): what a scene's run compiles
    key: str = ""


def lookup_model(ref: str, base=None) -> ModelInfo | None:
    """ModelInfo of the model a scene names, or None when no model has that name.

    ``ref`` is a built-in or entry-point name, a path (relative to ``base``, the scene's folder)
    or ``package.module:attribute`` (:func:`mechgen.models.resolve`). A path or module that
    does not exist, and a model file that fails to import, raise their InputError.
    """
    try:
        source = models.resolve(ref, base=base)
    except InputError:
        if models.is_path(ref) or ":" in ref:
            raise
        return None
    model = source.load()
    params = {p.name: ParamInfo(p.default, p.choices, p.integer, p.below) for p in model.param_list}
    coords = model.coordinates_all
    if model.is_lattice:
        n = int(model.param(model.chain_spec.sites).default)
        coords = tuple(f"{model.chain_spec.coordinate}_{i + 1}" for i in range(n))
    cont = model.continuum
    return ModelInfo(model.name, params, coords, model.output_names, cont is not None,
                     cont.length if cont else None, dict(model.parts), model.complementary_fn is not None,
                     model.field_names, tuple(o.name for o in getattr(model, "shape_outputs", ())), source.key)
