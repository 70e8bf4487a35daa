"""``restitution``: an impact (mechgen.analyses.impact) over a grid, e.g. e(zeta) for every contact law.

Scene keys: ``over`` (as sweep's: parameter = [values] or {start, stop, num}; at most one choice
parameter, e.g. ``law``, and one numeric one, e.g. ``zeta``), the impact's keys (``t_end``, ``v0``,
``q0``, ``method``, ``rtol``, ``atol``, ``coordinate``, ``contact_mode``, ``force_output``, ``loop``), ``hysteresis``
(how many values of the numeric parameter also record the force-penetration curve, spread over its
grid; default 4, 0 for none; or a list of values: the grid's nearest), ``samples`` (points per curve), ``progress`` and ``max_seconds`` (the whole
grid, as sweep's). A numeric parameter of ``over`` that the command line sets (``--set zeta=0.3``)
is run at that single value.

Outputs: the numeric parameter's values under its own name (``zeta``), and ``restitution``,
``contact_duration``, ``energy_lost`` and ``released``: objects mapping each choice (``kelvin_voigt``
...) to a list aligned with it (plain lists without a choice parameter); ``hysteresis`` (per choice,
a list of {parameter value, ``penetration``, ``force``}); ``impacts`` (the analysis's ``seconds`` in the
result, divided by it, is the time per impact).
"""
from __future__ import annotations

from mechgen.analyses import figures, schema, summary
from mechgen.analyses.context import NAME, POINTS, PointRunner, run_at_point
from mechgen.analyses.impact import SCHEMA as IMPACT, hybrid_only, needs
from mechgen.analyses.parameters import with_free_params
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import Option
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.core.sweep import sweep
from mechgen.scene.values import fail

MEASURED = ("restitution", "contact_duration", "energy_lost", "released")

SCHEMA = {**{k: v for k, v in IMPACT.items() if k != "curve"},
          "over": Option(schema.over, schema.REQUIRED, "a table: parameter = [values] or {start, stop, num}",
                         doc="the grid, as sweep's: at most one choice parameter (law) and one numeric one "
                         "(zeta)"),
          "hysteresis": Option(lambda ctx, key, value: _hysteresis(ctx, key, value), 4,
                               doc="how many values of the numeric parameter, spread over its grid, also record "
                               "the force-penetration curve (0: none), or a list of values"),
          "progress": Option(schema.boolean, True, doc="draw a progress bar on stderr (when it is a terminal and "
                             "the grid lasts over 2 s)")}


def _hysteresis(ctx, key: str, value: object):
    """A count (>= 0) of curves spread over the grid, or a list of values of the numeric parameter."""
    if isinstance(value, list):
        if not value:
            raise fail(ctx.file, key, "empty array", "a count, or a non-empty array of parameter values")
        return [schema.number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    return schema.int_at_least(ctx, key, value, 0)


def check(ctx, base: str, options: dict) -> None:
    """At most one choice and one numeric parameter; a numeric one set by --set runs at that value only;
    adds ``grid`` (choice outermost)."""
    hybrid_only(ctx, base, options)
    choice = [p for p in options["over"] if not ctx.model.params[p].numeric]
    numeric = [p for p in options["over"] if ctx.model.params[p].numeric]
    if len(choice) > 1 or len(numeric) > 1:
        raise fail(ctx.file, f"{base}.over", f"over names {len(choice)} choice and {len(numeric)} numeric "
                   "parameters", "at most one choice parameter (the laws) and one numeric one (zeta)")
    written = getattr(ctx, "written", {}) or {}
    for name in numeric:
        where = written.get(name)
        if where is not None and str(where[1]).startswith("--set"):
            options["over"][name] = [ctx.params[name]]
    order = choice + numeric
    options["over"] = {k: options["over"][k] for k in order}
    options["grid"] = schema.grid(options["over"])


def frees(options: dict) -> list[str]:
    """The numeric parameter of the grid (choices recompile)."""
    return [p for p in options["over"] if options["over"][p] and not isinstance(options["over"][p][0], str)]


def _at_point(task: tuple) -> dict:
    system, kind, options, point = task
    return run_at_point(kind, with_free_params(system, point, key="grid"), options)


def curve_points(values: list, count) -> set:
    """Indices of ``count`` values spread evenly over a grid of ``len(values)`` (ends included), or, for a list
    of parameter values, of the grid values nearest to them."""
    if isinstance(count, list):
        return {int(min(range(len(values)), key=lambda i: abs(values[i] - v))) for v in count} if values[0] is not None \
            else {0}
    if count <= 0 or not values:
        return set()
    if count >= len(values):
        return set(range(len(values)))
    return {round(i * (len(values) - 1) / (count - 1)) for i in range(count)} if count > 1 else {0}


def run_restitution(system, options: dict, context: dict) -> dict:
    """Every grid point's impact (structural choices recompiled through the scene's point runner)."""
    over = options["over"]
    names = list(over)
    choice = next((n for n in names if isinstance(over[n][0], str)), None)
    numeric = next((n for n in names if n != choice), None)
    values = over[numeric] if numeric else [None]
    curves = curve_points(values, options.get("hysteresis", 4))
    base = {k: v for k, v in options.items() if k in IMPACT}
    points = context.get(POINTS) or PointRunner(_at_point, lambda kind, opts, point: (system, kind, opts, point))
    grid = options["grid"]
    tasks = []
    for point in grid:
        index = values.index(point[numeric]) if numeric else 0
        tasks.append(points.task("impact", {**base, "curve": index in curves}, point))
    budget = Budget("restitution impacts", unit="points",
                    seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    results = sweep(points.evaluate, tasks, workers=0, progress=options.get("progress", True),
                    desc=context.get(NAME, "restitution"), budget=budget, labels=grid)
    keys = [point[choice] for point in grid] if choice else [None] * len(grid)
    out: dict = {numeric or "point": list(values)}
    for what in MEASURED:
        table: dict = {}
        for key, r in zip(keys, results):
            table.setdefault(key, []).append(r[what])
        out[what] = table if choice else table[None]
    hyst: dict = {}
    for key, point, r in zip(keys, grid, results):
        if "force_series" in r:
            hyst.setdefault(key, []).append({numeric or "point": point.get(numeric), "penetration":
                                             r["penetration_series"], "force": r["force_series"]})
    out["hysteresis"] = hyst if choice else hyst.get(None, [])
    out["impacts"] = len(grid)
    return out


def summary_lines(outputs: dict) -> list[str]:
    """The measured objects cut at 4 values, the grid's extent and the time per impact."""
    return summary.output_lines(outputs, skip=("hysteresis",), width=4)


def plot(plt, a: dict, path) -> list:
    """e against the numeric parameter per choice, and the hysteresis curves (second figure)."""
    out = a["outputs"]
    name = next(iter(out))
    x = out[name]
    table = out["restitution"] if isinstance(out["restitution"], dict) else {"": out["restitution"]}
    fig, ax = plt.subplots(figsize=(6, 4))
    for key, es in table.items():
        ax.plot(x, es, label=key)
    ax.set_xlabel(figures.labelled(a, name))
    ax.set_ylabel("coefficient of restitution e")
    ax.legend(fontsize=8)
    ax.set_title(a["name"])
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    written = [path]
    hyst = out.get("hysteresis") or {}
    hyst = hyst if isinstance(hyst, dict) else {"": hyst}
    if any(hyst.values()):
        second = path.with_name(path.stem + "_hysteresis" + path.suffix)
        fig, axes = plt.subplots(1, len(hyst), figsize=(3.2 * len(hyst), 3.4), squeeze=False, sharey=True)
        for col, (ax, (key, curves)) in enumerate(zip(axes[0], hyst.items())):
            for c in curves:  # the same parameter values in every panel: one legend, the first panel's
                ax.plot(c["penetration"], c["force"], label=f"{name} = {c[name]:.3g}" if col == 0 else None)
            ax.set_title(key, fontsize=9)
            ax.set_xlabel("penetration")
        axes[0, 0].set_ylabel("force")
        axes[0, 0].legend(fontsize=7)
        fig.suptitle(f"{a['name']}: force against penetration", fontsize=9)
        fig.tight_layout()
        fig.savefig(second, dpi=120)
        plt.close(fig)
        written.append(second)
    return written


register(AnalysisKind("restitution", SCHEMA, run_restitution, needs, summary_lines, check=check, frees=frees,
                      plot=plot))
