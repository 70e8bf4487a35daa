"""What a scene compiles: its :class:`~mechgen.pipeline.CompileRequest` s, planned from model facts only.

:func:`plan_scene` is the one place that decides which kernels a scene's analyses need and
with which fixed values, free names and active coordinates: ``mechgen run`` compiles its
``main`` request (and :func:`point_request` for a sweep point that changes a structural choice),
and ``mechgen regen`` writes every request of every shipped scene (:meth:`ScenePlan.requests`).
Nothing here imports the model or sympy: the facts come from :func:`mechgen.scene.info.model_info`.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from mechgen import models
from mechgen.pipeline import CompileRequest, file_digest
from mechgen.analyses.registry import needs
from mechgen.scene.info import ModelInfo, model_info


@dataclass(frozen=True)
class ScenePlan:
    """A scene's compile requests: ``main`` for its system, ``points`` for sweep points that change structure.

    ``points`` maps an analysis name to one request per grid point (None where the point keeps
    ``main``'s structure).
    """

    main: CompileRequest
    points: dict
    source: models.ModelSource
    info: ModelInfo

    def requests(self) -> list[CompileRequest]:
        """Every distinct request, ``main`` first, in first-use order."""
        out = [self.main]
        for reqs in self.points.values():
            out += [r for r in reqs if r is not None and r not in out]
        return out


def request_for(info: ModelInfo, digest: str, values: dict, *, free=(), active=None, kernels=(),
                backend: str = "c", cse: bool = True, source: str = "") -> CompileRequest:
    """The request of a specialisation, as :func:`mechgen.symbolic.specialize.specialize` would make it.

    Every numeric parameter not free is fixed (to ``values`` or its default); part parameters are
    always free; free names and active coordinates follow the declaration order.
    """
    free = tuple(free) + tuple(n for n in info.part_params if n not in free)
    ordered = tuple(n for n in info.params if n in free)
    fixed = tuple(sorted((n, values.get(n, p.default)) for n, p in info.params.items() if n not in ordered))
    starts = tuple((n, values.get(n, info.params[n].default)) for n in ordered)
    if active is not None:
        active = tuple(c for c in info.coordinates_all if c in active)
    kind = ("field" if info.continuum else "plane" if info.plane_fields else "lattice" if info.chain
            else "lumped")
    return CompileRequest(info.name, digest, fixed, ordered, active, tuple(sorted(set(kernels))), backend, cse,
                          tuple(n for n, p in info.params.items() if p.runtime), starts, kind,
                          tuple(n for n, p in info.params.items() if p.numeric),
                          info.chain[1] if info.chain else None, source)


def point_request(main: CompileRequest, info: ModelInfo, point: dict) -> CompileRequest | None:
    """The request of a sweep point that sets structural (non-numeric) parameters, None when it sets none."""
    sizes = {k: v for k, v in point.items() if not info.param(k).numeric}
    if not sizes:
        return None
    values = {**dict(main.values), **sizes}
    return replace(main, values=tuple(sorted(values.items())))


def plan_scene(scn, *, backend: str | None = None, base: str | Path | None = None) -> ScenePlan:
    """The compile requests of a loaded scene (:class:`mechgen.scene.load.Scene`)."""
    base = Path(scn.path).parent if base is None and scn.path else base
    source = models.resolve(scn.source or scn.model, base=base)
    info = model_info(source.key)
    backend = backend or scn.backend
    kernels = set().union(*(needs(a.kind, a.options, internal=info.internals) for a in scn.analyses))
    free = tuple(n for n in scn.free if info.param(n).numeric)
    main = request_for(info, file_digest(source.file), dict(scn.params), free=free, active=scn.active,
                       kernels=kernels, backend=backend, source=source.key)
    points = {a.name: [point_request(main, info, p) for p in a.options["grid"]]
              for a in scn.analyses if "grid" in a.options}
    return ScenePlan(main, points, source, info)


def derive_with(source: models.ModelSource, request: CompileRequest):
    """A ``derive_with`` for :func:`mechgen.pipeline.compile_request`: imports the model and specialises it."""
    def load():
        from mechgen.symbolic.specialize import specialize

        model = source.load()
        return model, specialize(model, {**dict(request.values), **dict(request.free_values)}, free=request.free,
                                 active=request.active)
    return load
