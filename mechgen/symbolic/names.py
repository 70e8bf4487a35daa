"""Identifier rules for user-chosen names (models, parameters, coordinates, outputs).

Names reach generated code only as comments and as keys of the kernel spec;
array accesses are generated from positions. Still, every name is checked here
so that a hostile string is an error at declaration time, never text in a file.

Two rules:

* :func:`check_identifier` (at each declaration): a plain ASCII identifier, not a Python or
  C keyword, not starting with ``_``;
* :func:`check_model_names` (when a model is specialised, and again where it is derived): no
  declared name equals a name mechgen derives from the model's declarations or reports beside
  its outputs -- the velocity ``<q>_dot`` and acceleration ``<q>_ddot`` of a coordinate, a
  chain's neighbours ``<u>_a``, ``<u>_b`` (and their ``_dot``), a field's jets ``<f>_s``,
  ``<f>_sst`` ..., test jets ``test_<jet>``, stress resultants ``n_<f>``, the position ``s``,
  the built-in outputs (:data:`BUILTIN_OUTPUTS`, :data:`STEADY_OUTPUTS`) and the keys the
  analyses put beside the model's outputs in a result (:data:`RESULT_KEYS`). Otherwise the
  declared symbol silently *becomes* the derived one (a coordinate ``theta_dot`` beside
  ``theta`` is theta's velocity), or an output is overwritten in the result.
"""
from __future__ import annotations

import keyword
import re
import sys
from pathlib import Path

from mechgen.errors import ModelError

_SYMBOLIC = Path(__file__).resolve().parent
_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}\Z")
RESERVED = frozenset({"t", "pi", "e", "I", "S", "oo", "nan", "zoo"})
#: C99/C11 keywords (a name is refused like a Python keyword: export builds C identifiers from names)
C_KEYWORDS = frozenset("""auto break case char const continue default do double else enum extern float for goto if
inline int long register restrict return short signed sizeof static struct switch typedef union unsigned void volatile
while""".split())
#: the outputs every model has (mechgen.symbolic.derive, mechgen.symbolic.field)
BUILTIN_OUTPUTS = ("kinetic_energy", "potential_energy", "energy")
#: the outputs a continuum's steady forms add (mechgen.symbolic.steady)
STEADY_OUTPUTS = ("potential_density", "hamiltonian")
#: the keys analyses report beside a model's outputs in one result (steady, simulate, sweep, continuation,
#: stability): an output of one of these names would be overwritten (mechgen/analyses/*.py)
RESULT_KEYS = ("iterations", "residual_norm", "coordinates", "reactions", "method", "s", "deflection", "shapes",
               "verdict", "frequencies", "eigenvalues", "growth_rate", "refinement", "rigid_modes", "energy_drift",
               "t_end", "mode_energies", "t", "energy_series", "grid", "parameter", "shape_outputs", "branch", "folds",
               "events", "final_mode", "t_final", "mode_series", "trajectory", "series_note", "zeno", "loop", "plot",
               "energy_balance_error", "work", "dissipated", "energy_note", "nodal", "probe_displacement")
#: a jet's suffix after ``<field>_``: space derivatives, then at most two time derivatives
JET_SUFFIX = re.compile(r"(s*)(t{0,2})\Z")
#: what the ends of a continuum's outputs are reported as (mechgen.analyses.bvp_states)
_OUTPUT_ENDS = ("start", "end", "max", "min")


def declaring_file() -> str | None:
    """The file of the innermost caller outside mechgen.symbolic: where a declaration was written.

    None when that caller is not a file (an interactive session).
    """
    frame = sys._getframe(1)
    while frame is not None:
        name = frame.f_code.co_filename
        if name != "<string>" and Path(name).resolve().parent != _SYMBOLIC:  # "<string>": a dataclass __init__
            return name if Path(name).is_file() else None
        frame = frame.f_back
    return None


def check_identifier(name: object, *, what: str, file: str | None = None) -> str:
    """Return ``name`` if it is a plain identifier, else raise :class:`ModelError`.

    Accepted: a letter, then up to 63 letters, digits or underscores; not a
    Python or C keyword; no leading underscore (reserved for generated code). The
    error names ``file``, else the file the declaration was written in.
    """
    if isinstance(name, str) and keyword.iskeyword(name):
        raise ModelError(f"{what} name {name!r} is a Python keyword, not a valid identifier "
                         f"(.{name} cannot be written in Python)", file=file or declaring_file(), key=what,
                         expected=f"a name that is not a Python keyword, e.g. {name}_")
    if isinstance(name, str) and name in C_KEYWORDS:
        raise ModelError(f"{what} name {name!r} is a C keyword (generated and exported C names things after "
                         "the model's names)", file=file or declaring_file(), key=what,
                         expected=f"a name that is not a C or Python keyword, e.g. {name}_")
    if not isinstance(name, str) or not _IDENT.match(name):
        raise ModelError(f"{what} name {name!r} is not a valid identifier", file=file or declaring_file(), key=what,
                         expected="a letter followed by letters, digits or underscores (at most 64)")
    return name


def jet_of(name: str, fields) -> tuple[str, int, int] | None:
    """(field, space order, time order) of a jet name such as ``w_sst`` among ``fields``, or None.

    The longest field name that ``name`` starts with wins (fields ``w`` and ``w2``: ``w2_s`` is of w2).
    """
    for f in sorted(fields, key=len, reverse=True):
        if name == f:
            return f, 0, 0
        if name.startswith(f + "_"):
            m = JET_SUFFIX.match(name[len(f) + 1:])
            if m and m.group(0):
                return f, len(m.group(1)), len(m.group(2))
    return None


def declared_names(model) -> list[tuple[str, str]]:
    """(name, what) of every name a model declares, in declaration order."""
    out = [(p.name, "parameter") for p in model.param_list]
    out += [(c, "coordinate") for c in model.coordinate_names]
    if model.chain_spec is not None:
        out.append((model.chain_spec.coordinate, "chain coordinate"))
    out += [(f, "field") for f in model.field_names]
    out += [(i.name, "internal variable") for i in model.internals]
    out += [(o.name, "output") for o in model.outputs]
    out += [(o.name, "shape output") for o in model.shape_outputs]
    return out


def _derived_by(name: str, model) -> str | None:
    """What ``name`` is among the names mechgen derives from ``model``'s declarations, or None."""
    for c in model.coordinate_names:
        if name == f"{c}_dot":
            return f"the velocity of coordinate {c}"
        if name == f"{c}_ddot":
            return f"the acceleration of coordinate {c}"
    if model.chain_spec is not None:
        u = model.chain_spec.coordinate
        derived = {f"{u}_dot": f"the velocity of chain coordinate {u}",
                   f"{u}_ddot": f"the acceleration of chain coordinate {u}",
                   f"{u}_a": f"the bond's first site {u}_a (a.q)", f"{u}_b": f"the bond's second site {u}_b (b.q)",
                   f"{u}_a_dot": f"the velocity of the bond's first site (a.v)",
                   f"{u}_b_dot": f"the velocity of the bond's second site (b.v)"}
        if name in derived:
            return derived[name]
    fields = model.field_names
    if fields:
        if name == "s":
            return "the position s along the continuum"
        jet = jet_of(name, [f for f in fields if f != name])  # a field w_s beside w is w's slope
        if jet is not None and jet[1:] != (0, 0):
            return f"the jet {name} of field {jet[0]} (u.{name}: derivatives of {jet[0]})"
        if name.startswith("test_") and jet_of(name[5:], fields) is not None:
            return f"the test jet {name} of the weak form"
        if name.startswith("n_") and name[2:] in fields:
            return f"the stress resultant n_{name[2:]} conjugate to {name[2:]}_s (the steady stress form)"
        if name.startswith("bc_") and any(name.startswith(f"bc_{f}_") for f in fields):
            return "a boundary value output bc_<field>_<order>_<end> of the steady forms"
    return None


def output_clash(name: str, model) -> str | None:
    """What an output called ``name`` would collide with in a model's results, or None."""
    if name in BUILTIN_OUTPUTS:
        return f"the built-in output {name} (every model reports {', '.join(BUILTIN_OUTPUTS)})"
    if model.field_names and name in STEADY_OUTPUTS:
        return f"the steady forms' output {name}"
    if name in RESULT_KEYS:
        return f"the result key {name} that analyses report beside the outputs"
    if model.field_names:
        for o in model.outputs:
            for end in _OUTPUT_ENDS:
                if name == f"{o.name}_{end}":
                    return f"the value {name} that steady states report for output {o.name}"
        for f in model.field_names:
            if name in (f"{f}_s_start", f"{f}_s_end"):
                return f"the end slope {name} that steady states report for field {f}"
    return None


def name_clash_error(model, name: str, what: str, clash: str) -> ModelError:
    """The error for a declared ``name`` that clashes with ``clash`` (a derived name or a reported key)."""
    return ModelError(f"{what} name {name!r} of model {model.name} clashes with {clash}: the two would be one "
                      "symbol or one result entry", file=model.file, key=name,
                      expected=f"a name mechgen does not derive or report, e.g. {name}_{what.split()[-1][0]}")


def check_model_names(model) -> None:
    """Raise :class:`ModelError` (naming the model's file, the name and the clash) when a declared name
    equals a derived name or a reported key of ``model`` (see the module doc)."""
    for name, what in declared_names(model):
        clash = _derived_by(name, model)
        if clash is None and what in ("output", "shape output"):
            clash = output_clash(name, model)
        if clash is not None:
            raise name_clash_error(model, name, what, clash)
