"""``mechgen.compile``: a model (or a reference to one) and parameter values in, an immutable compiled system out.

::

    import mechgen
    pendulum = mechgen.compile("spring_pendulum", {"m": 2.0, "k": 50.0})
    mats = pendulum.linear([1.0 + 2.0 * 9.81 / 50.0, 0.0])      # M, D, G, K at an operating point
    stiffer = pendulum.with_params(k=80.0)                       # a new system; ``pendulum`` is unchanged

The system (:class:`mechgen.runtime.core.system.System`, or
:class:`mechgen.runtime.fields.continuum.FieldSystem` for a continuum) gives ``linear(q, v)`` (M, D, G, K),
``residual(q, v, a)``, ``tangent(q, v, a)`` (dr/dq, dr/dv, dr/da) and ``outputs(q, v)`` as numpy
arrays. By default every numeric parameter stays a kernel input, so that ``with_params`` is cheap
(a new parameter vector); a name fixed at compile time (``free`` narrower than all, or a
structural choice such as a boundary condition) is folded into the kernels, and ``with_params``
on it recompiles through this same function.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from mechgen.errors import InputError, did_you_mean


def compile(model, params: Mapping | None = None, *, free=None, backend: str = "c", kernels=None,  # noqa: A001
            segments=None, parts=None):
    """Compile ``model`` at the values ``params`` and return the immutable compiled system.

    Args:
        model: a :class:`~mechgen.symbolic.model.Model`, or a reference for
            :func:`mechgen.models.load_model` (a built-in name, a path to a ``.py`` file,
            ``package.module:attribute``).
        params: parameter values by name (numbers, choices, sizes); the others keep their defaults.
        free: the numeric parameters kept as kernel inputs (default: every numeric one); the
            others are folded into the kernels as constants. Parameters set per segment and
            those of part kinds are always kept free.
        backend: "c", "numpy" or "casadi" (C falls back to numpy, with a warning, without a compiler).
        kernels: the kernels to build (default: every kernel of the model; a continuum's steady
            boundary-value kernels ``bvp_*``/``hbvp_*`` only when asked for).
        segments: a continuum's uniform pieces from s = 0: :class:`~mechgen.runtime.fields.mesh.Segment`
            or mappings ``{"length", "elements", <numeric parameter>: value ...}``.
        parts: lumped parts placed along a continuum: :class:`~mechgen.runtime.fields.mesh.Part` or
            mappings ``{"kind", "at", <part parameter>: value ...}``.

    Returns:
        The system, whose ``with_params(**values)`` gives a new system and never changes it.
    """
    from mechgen import models
    from mechgen.codegen.kernel_names import all_kernels
    from mechgen.pipeline import compile_model
    from mechgen.symbolic.model import Model
    from mechgen.symbolic.specialize import specialize

    if isinstance(model, str):
        model = models.load_model(model)
    if not isinstance(model, Model):
        raise InputError(f"model is {type(model).__name__}", key="model",
                         expected="a mechgen.Model or a model reference (a name, a .py path, module:attribute)")
    values = _values(model, params)
    layout = _layout(model, segments, parts, values)
    free = _free(model, free, layout)
    spec = specialize(model, values, free=free)
    wanted = all_kernels(model) if kernels is None else _kernel_names(kernels)
    system, _ = compile_model(model, spec, kernels=set(wanted), backend=backend)
    runtime = {p.name for p in model.param_list if p.runtime}
    sites = model.chain_spec.sites if model.is_lattice else None
    folded = tuple(p.name for p in model.param_list
                   if p.name not in spec.free and p.name not in runtime and p.name != sites)

    def rebuild(current, changes: dict):
        """The model recompiled with ``changes`` on top of ``current``'s values (same free set, kernels, layout)."""
        now = {**values, **current.param_values(), **changes}
        here = getattr(current, "layout", None)
        return compile(model, now, free=free, backend=backend, kernels=wanted,
                       segments=here.segments if here is not None else None,
                       parts=here.parts if here is not None else None)

    from mechgen.scene.info import info_of_model

    # the model's facts travel with the system: the analyses check options against them, and a model object
    # (declared in a notebook) has no reference they could be looked up by
    system = replace(system, rebuild=rebuild, folded=folded, facts=info_of_model(model))
    if layout is not None:
        system = system.with_layout(layout)
    return system


def _values(model, params) -> dict:
    """The given values, checked against the model's parameters (names, numbers, choices, sizes)."""
    from mechgen.runtime.core.system import number

    if params is None:
        return {}
    if not isinstance(params, Mapping):
        raise InputError(f"params is {type(params).__name__}", key="params",
                         expected="a mapping of parameter names to values")
    known = {p.name: p for p in model.param_list}
    unknown = [k for k in params if k not in known]
    if unknown:
        raise InputError(f"model {model.name} has no parameter {', '.join(map(repr, unknown))}"
                         f"{did_you_mean(unknown[0], known)}", key=unknown[0],
                         expected="one of: " + ", ".join(known))
    out = {}
    for name, value in params.items():
        prm = known[name]
        if prm.is_choice:
            if value not in prm.choices:
                raise InputError(f"parameter {name!r} = {value!r} of model {model.name} is not one of its choices",
                                 key=name, expected="one of: " + ", ".join(map(str, prm.choices)))
            out[name] = value
        elif prm.integer:
            if isinstance(value, bool) or not isinstance(value, int) and not (
                    isinstance(value, float) and value.is_integer()):
                raise InputError(f"parameter {name!r} = {value!r} of model {model.name} is not an integer",
                                 key=name, expected="an integer")
            out[name] = int(value)
        else:
            out[name] = number(name, value)
    return out


def _free(model, free, layout) -> tuple[str, ...]:
    """The free numeric parameters: the given ones (checked) or all, plus those the segments set."""
    numeric = [p.name for p in model.param_list if p.is_numeric]
    if free is None:
        chosen = list(numeric)
    else:
        if isinstance(free, str):
            free = (free,)
        chosen = list(free)
        bad = [n for n in chosen if n not in numeric]
        if bad:
            raise InputError(f"free names {', '.join(map(repr, bad))}, which are no numeric parameters of model "
                             f"{model.name}", key="free", expected="numeric parameters: " + ", ".join(numeric))
    if layout is not None:
        chosen += [n for seg in layout.segments for n in seg.values if n not in chosen]
    return tuple(n for n in numeric if n in chosen)


def _kernel_names(kernels) -> tuple[str, ...]:
    if isinstance(kernels, str):
        kernels = (kernels,)
    names = tuple(kernels)
    if not names or not all(isinstance(k, str) for k in names):
        raise InputError(f"kernels is {kernels!r}", key="kernels", expected="kernel names (residual, linear, ...)")
    return names


def _layout(model, segments, parts, values: dict):
    """A :class:`~mechgen.runtime.fields.mesh.Layout` of the given segments and parts (None when there are none)."""
    from mechgen.runtime.fields.mesh import Layout, Part, Segment

    if not segments and not parts:
        return None
    if not model.is_field:
        raise InputError(f"model {model.name} is not a continuum", key="segments" if segments else "parts",
                         expected="segments and parts only for continua")
    out_segments = []
    for i, seg in enumerate(segments or (), 1):
        if isinstance(seg, Mapping):
            rest = {k: v for k, v in seg.items() if k not in ("length", "elements")}
            try:
                seg = Segment(float(seg["length"]), int(seg["elements"]), rest)
            except (KeyError, TypeError, ValueError):
                raise InputError(f"segment {i} is {dict(seg)!r}", key=f"segments[{i}]",
                                 expected="length (m), elements (an integer) and numeric parameter values") from None
        if not isinstance(seg, Segment) or not seg.length > 0 or seg.elements < 1:
            raise InputError(f"segment {i} is {seg!r}", key=f"segments[{i}]",
                             expected="a Segment (or mapping) with length > 0 and elements >= 1")
        out_segments.append(seg)
    kinds = getattr(model, "parts", None) or {}
    out_parts = []
    for i, part in enumerate(parts or (), 1):
        if isinstance(part, Mapping):
            rest = {k: v for k, v in part.items() if k not in ("kind", "at")}
            try:
                part = Part(str(part["kind"]), float(part["at"]), rest)
            except (KeyError, TypeError, ValueError):
                raise InputError(f"part {i} is {dict(part)!r}", key=f"parts[{i}]",
                                 expected="kind, at (m) and the part's parameter values") from None
        if not isinstance(part, Part):
            raise InputError(f"part {i} is {part!r}", key=f"parts[{i}]", expected="a Part or a mapping")
        if part.kind not in kinds:
            raise InputError(f"part kind {part.kind!r} is not declared by model {model.name}", key=f"parts[{i}].kind",
                             expected="one of: " + (", ".join(sorted(kinds)) or "none (the model declares no parts)"))
        out_parts.append(part)
    _check_parts(model, out_parts, values)
    return Layout(tuple(out_segments), tuple(out_parts))


def _check_parts(model, parts, values: dict) -> None:
    """Each part's values against its kind's declared checks (Model.part), as a scene's [[parts]] are: InputError at
    ``parts[i].<key>``; a value the part leaves out is the compile's ``<kind>_<name>`` or the declared default."""
    if not any(model.part_checks.get(part.kind) for part in parts):
        return
    from mechgen.scene.info import info_of_model
    from mechgen.scene.layout import check_part

    info = info_of_model(model)
    for i, part in enumerate(parts, 1):
        check_part(None, f"parts[{i}]", info, part.kind, dict(part.values), values)
