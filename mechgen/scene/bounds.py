"""Load-time bounds of parameter values and sizes, reported at the key the user wrote.

A model declares what its parameters may be (``Param(positive=True)``, ``below=``, a size's
integer count; :class:`mechgen.scene.info.ParamInfo` carries these facts). The scene loader
checks every value a scene or a ``--set`` flag gives against them before anything is compiled or
allocated, so that a negative length is refused at ``params.L`` and not later at an internal
key (``discretisation``, ``M``), where the runtime's own checks stay as a second line of defence.

Rules, for a value v the scene wrote (model defaults are the model's business and not checked):

* every number: v = 0 or |v| >= 2.2250738585072014e-308 (sys.float_info.min); a subnormal
  double (5e-324) is too small to be a physical value and has lost its precision;
* ``positive``: v > 0; ``minimum`` <= v <= ``maximum`` where declared; v < ``below``;
* a size (an integer the kernels never see: a chain's sites, a continuum's N, quadrature):
  v >= 0, v >= 1 for a count of sites or elements, and v <= a safety limit (:data:`LIMITS`) that
  a scene may raise in its ``[limits]`` table::

      [limits]
      size = 20_000_000      # every size parameter (default 10 000 000)
      quadrature = 200       # Gauss points per element (default 100)
      samples = 5_000_000    # samples a simulate analysis stores (default 1 000 000)
      rows = 5_000_000       # rows of a fit's data (default 1 000 000)

  A limit is only a guard against a typo (N = 1e308, quadrature = 100000 is a 74.5 GiB
  Gauss table); the memory a large size needs is estimated where it is allocated.
"""
from __future__ import annotations

import sys
from typing import Mapping

from mechgen.scene.values import ModelInfoLike, fail, is_choice, is_number, join, listing, show, type_name

#: default safety limits; ``size`` applies to every size parameter without an entry of its own
LIMITS = {"size": 10_000_000, "quadrature": 100, "samples": 1_000_000, "rows": 1_000_000}
#: the largest limit a scene may set (beyond it an int no longer converts exactly to a float)
MAX_LIMIT = 2**53
TINY = sys.float_info.min


def is_size(info) -> bool:
    """A runtime size: an integer that is neither a choice nor a number the kernels see."""
    return bool(info.integer) and not getattr(info, "numeric", True) and not is_choice(info)


def number_text(value) -> str:
    """A number for messages: an integer of more than 15 digits in float notation (1e+308)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**15:
        return f"{float(value):.6g}"
    return repr(value)


def _whole(bound) -> str:
    return str(int(bound)) if float(bound).is_integer() else repr(bound)


def scene_limits(file: str, data: dict, model: ModelInfoLike) -> dict[str, int]:
    """The scene's ``[limits]`` over :data:`LIMITS`: keys ``size``, ``samples``, ``rows`` or a size parameter's
    name; values integers from 1 to 2**53."""
    table = data.get("limits", {})
    if not isinstance(table, dict):
        raise fail(file, "limits", f"limits is {type_name(table)}", "a table of name = largest value")
    sizes = [n for n, info in model.params.items() if is_size(info)]
    allowed = sorted({*LIMITS, *sizes})
    out = dict(LIMITS)
    for name, value in table.items():
        key = join("limits", name)
        if name not in allowed:
            raise fail(file, key, f"unknown limit {show(name)}", "one of: " + listing(allowed))
        if not is_number(value) or not 1 <= value <= MAX_LIMIT or not float(value).is_integer():
            raise fail(file, key, f"limit is {show(value) if is_number(value) else type_name(value)}",
                       f"an integer from 1 to {MAX_LIMIT}")
        out[name] = int(value)
    return out


def size_limit(limits: Mapping[str, int], name: str) -> tuple[int, str]:
    """The safety limit of a size parameter and the ``[limits]`` key that raises it."""
    if name in limits and name not in ("size", "samples", "rows"):
        return limits[name], name
    return limits["size"], "size"


def check_value(file: str | None, key: str, name: str, info, value, limits: Mapping[str, int]) -> None:
    """Refuse a value outside the parameter's declared bounds (rules in the module docstring)."""
    if is_choice(info) or not is_number(value):
        return
    text = f"{name} = {number_text(value)}"
    if value != 0 and abs(value) < TINY:
        raise fail(file, key, f"{text} is a subnormal number, too small to be a physical value "
                   f"(below {TINY:.17g}, where doubles lose precision)",
                   f"0 or a value of magnitude at least {TINY:.4g}")
    if getattr(info, "positive", False) and not value > 0:
        raise fail(file, key, f"{text} is not positive; parameter {name} is declared positive",
                   "a value > 0")
    low, high = getattr(info, "minimum", None), getattr(info, "maximum", None)
    if is_size(info):
        limit, limit_key = size_limit(limits, name)
        floor = 0 if low is None else low
        top = limit if high is None else min(high, limit)
        if not floor <= value <= top:
            hint = ""
            if value > top and top == limit and (high is None or high > limit):
                hint = (f" ({limit} is a safety limit against typos, not a property of the model: "
                        f"raise it with [limits] {limit_key} = ... in the scene)")
            raise fail(file, key, f"{text} is outside the range of the size {name}",
                       f"an integer from {_whole(floor)} to {_whole(top)}{hint}")
        return
    if low is not None and not value >= low:
        raise fail(file, key, f"{text} is below the minimum {low!r} of parameter {name}", f"a value >= {low!r}")
    if high is not None and not value <= high:
        raise fail(file, key, f"{text} is above the maximum {high!r} of parameter {name}", f"a value <= {high!r}")
    below = getattr(info, "below", None)
    if below is not None and not value < below:
        raise fail(file, key, f"{text} is not below {below!r}", f"a value below {below!r}")


def check_params(model: ModelInfoLike, values: Mapping[str, object], sources: Mapping[str, tuple],
                 limits: Mapping[str, int]) -> None:
    """Check every value the scene or a ``--set`` wrote (``sources``: name -> (file, key))."""
    for name, (file, key) in sources.items():
        check_value(file, key, name, model.params[name], values[name], limits)
