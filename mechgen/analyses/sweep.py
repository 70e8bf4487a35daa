"""``sweep``: another analysis repeated over a grid of parameter values.

Scene keys: ``over`` (parameter = [values] or {start, stop, num}; several parameters give their
cartesian product, the first outermost; at most 10^6 points), ``analysis`` (a table with the inner
``kind``: modes, stability, steady or simulate, and its keys), ``executor`` (``serial``, ``processes``
or ``dask``; left out: processes when ``workers`` > 1, else serial), ``workers`` (local processes, or
the workers of the Dask LocalCluster started for the run; 0: two), ``scheduler`` (Python calls only, with
dask: a running scheduler's address, ``tcp://host:port``, instead of a LocalCluster; a scene cannot name one,
``mechgen run --scheduler`` does), ``on_error`` (``record``, the
default: a failed point gets its error in ``status`` and None outputs and the sweep goes on; ``raise``:
the first failure stops the sweep), ``progress`` (a bar with the remaining time on stderr when it is a terminal and the sweep
lasts over 2 s) and ``max_seconds`` (the wall-time budget, default 600: the time of the whole grid
is estimated from its first points and a sweep that would take longer is refused once the estimate
is 2 s old, naming the estimate, the points done and the key). Outputs: ``grid`` (the points, a
list of {parameter: value}) plus one list per output of the inner analysis, in grid order, ``status``
(per point: ``ok`` or ``failed: <error>``), ``failed`` (their count), ``retried`` (the points run again
after a Dask worker was lost: each is still in the results once), ``executor`` and ``tasks`` (what the
executor ran: points, or Dask chunks of at least ~0.5 s of work). An inner analysis keeps its own budget
(``analysis.max_steps`` ...), per point.
"""
from __future__ import annotations

from pathlib import Path

from mechgen.analyses import figures, schema, summary
from mechgen.analyses.context import NAME, POINTS, PointRunner, run_at_point, scheduler_of
from mechgen.analyses.parameters import with_free_params
from mechgen.analyses.registry import AnalysisKind, get, register, sweepable_kinds
from mechgen.analyses.schema import ABSENT, REQUIRED, AnalysisSpec, Option
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.core.sweep import ON_ERROR, OK, SweepExecutor, sweep_points
from mechgen.scene.values import fail, type_name


def _inner(ctx, key: str, value: object) -> AnalysisSpec:
    """The analysis a sweep repeats: a table with ``kind`` (a sweepable kind) and that kind's keys."""
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table with kind and its options")
    kind = schema.analysis_kind(ctx, key, value, sweepable_kinds(value.get("kind")))
    options = schema.validate(ctx, key, get(kind), {k: v for k, v in value.items() if k != "kind"})
    options.update({k: v for k, v in get(kind).point_defaults.items() if k not in value})
    return AnalysisSpec(ctx.current, kind, options)


SCHEMA = {"over": Option(schema.over, REQUIRED, "a table: parameter = [values] or {start, stop, num}",
                         doc="the grid: parameter = [values] or {start, stop, num}; several parameters give "
                         "their cartesian product, the first outermost; at most 10^6 points"),
          "analysis": Option(_inner, REQUIRED, "a table with kind and its options",
                             doc="the inner analysis, a table with its kind (modes, stability, steady or "
                             "simulate) and its keys"),
          "progress": Option(schema.boolean, True, doc="draw a progress bar with the remaining time on stderr "
                             "(when it is a terminal and the sweep lasts over 2 s)"),
          "max_seconds": Option(schema.positive, ABSENT, doc="the wall-time budget of the whole grid (s, default "
                                "600), estimated from its first points"),
          **schema.executor_options(),
          "on_error": Option(schema.one_of("on_error", ON_ERROR), "record", doc="a failed point: record its "
                             "error in status and go on, or raise (stop the sweep)")}


def check(ctx, base: str, options: dict) -> None:
    """Adds ``grid``: the cartesian product of ``over``; a ``scheduler`` needs ``executor = "dask"``."""
    options["grid"] = schema.grid(options["over"])
    schema.check_executor(ctx, base, options)


def frees(options: dict) -> list[str]:
    """The swept parameters, and those the inner analysis keeps free."""
    names = list(options["over"])
    inner = options["analysis"]
    return names + [n for n in get(inner.kind).frees(inner.options) if n not in names]


def needs(options: dict, *, internal: bool) -> set[str]:
    """The inner analysis's kernels."""
    inner = options["analysis"]
    return get(inner.kind).needs(inner.options, internal=internal)


def _at_point(task: tuple) -> dict:
    """The inner analysis at one point on a copy of the system with the point's parameter values."""
    system, kind, options, point = task
    return run_at_point(kind, with_free_params(system, point, key="grid"), options)


def collect(grid: list[dict], results: list, status: list | None = None, retried: list | None = None) -> dict:
    """{"grid": grid, output: [value at each point] (None where the point failed), "status": ["ok" or
    "failed: ..."], "retried": [the points run again after their worker was lost]} (the outputs of the
    first point that succeeded)."""
    out: dict = {"grid": grid}
    first = next((r for r in results if r is not None), {})
    for key in first:
        out[key] = [None if r is None else r.get(key) for r in results]
    if status is not None:
        out["status"] = list(status)
        out["failed"] = sum(s != OK for s in status)
    if retried is not None:
        out["retried"] = [grid[i] for i in retried]
    return out


class Tasks:
    """The sweep's tasks, made when a point is reached (a grid of 10^6 points starts at once)."""

    def __init__(self, points: PointRunner, kind: str, options: dict, grid: list) -> None:
        self.points, self.kind, self.options, self.grid = points, kind, options, grid

    def __len__(self) -> int:
        return len(self.grid)

    def __getitem__(self, i: int):
        return self.points.task(self.kind, dict(self.options), self.grid[i])

    def __iter__(self):
        return (self[i] for i in range(len(self)))


def run_sweep(system, options: dict, context: dict) -> dict:
    """The inner analysis at every grid point (mechgen.runtime.core.sweep: serial, or ``workers`` processes).

    A scene's run gives the points through ``context[POINTS]`` (compiled again where a point sets a
    size); otherwise each point runs on a copy of ``system`` with the point's free parameters set.
    """
    inner = options["analysis"]
    points = context.get(POINTS) or PointRunner(_at_point, lambda kind, opts, point: (system, kind, opts, point))
    tasks = Tasks(points, inner.kind, dict(inner.options), options["grid"])
    budget = Budget(f"sweep of {inner.kind}", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    executor = SweepExecutor.of(options.get("executor"), options.get("workers", 0), scheduler_of(options, context))
    run = sweep_points(points.evaluate, tasks, executor=executor, progress=options.get("progress", True),
                       desc=context.get(NAME, "sweep"), budget=budget, labels=options["grid"],
                       on_error=options.get("on_error", "record"))
    out = collect(options["grid"], run.results, run.status, run.retried)
    out["executor"], out["tasks"] = executor.kind, run.tasks
    return out


def summary_lines(outputs: dict) -> list[str]:
    """Each output's list cut at 4 points (no eigenvalues or log decrements), then the grid's extent."""
    lines = summary.output_lines(outputs, skip=("eigenvalues", "log_dec"), width=4)
    grid = outputs.get("grid", [])
    if grid:
        lines.append(f"    grid: {len(grid)} points from {grid[0]} to {grid[-1]}")
    return lines


def plot(plt, a: dict, path: Path) -> list[Path]:
    """Frequencies against the swept parameter (a Campbell diagram when it is the spin speed Omega); with
    stability results, the verdicts as colours and the growth rates in a second panel."""
    grid = a["outputs"]["grid"]
    name = next(iter(grid[0])) if grid else "parameter"
    x = [g[name] for g in grid]
    growth = a["outputs"].get("growth_rate")
    fig, axes = plt.subplots(2 if growth else 1, 1, figsize=(6, 6 if growth else 4), squeeze=False, sharex=True)
    ax = axes[0, 0]
    verdicts = a["outputs"].get("verdict") or ["stable"] * len(x)
    colours = figures.VERDICT_COLOURS
    rows = a["outputs"].get("frequencies", [])
    ordered = len(x) >= 3 and all(isinstance(v, (int, float)) for v in x) and all(
        b > c for b, c in zip(x[1:], x[:-1]))
    if ordered:  # the k-th lowest frequency joined across the ordered points (thin: a crossing is not tracked)
        most = max((len(f) for f in rows if f is not None), default=0)
        for k in range(most):
            ys = [f[k] if f is not None and k < len(f) else float("nan") for f in rows]
            ax.plot(x, ys, "-", color="0.6", lw=0.7, zorder=1)
    for xi, freqs, verdict in zip(x, rows, verdicts):
        if freqs is None:  # a failed point
            continue
        ax.plot([xi] * len(freqs), freqs, ".", color=colours.get(verdict, "k"), ms=3, zorder=2)
    if name == "Omega" and x and isinstance(x[0], (int, float)):
        ax.plot([min(x), max(x)], [min(x), max(x)], "r--", lw=1, label="1x (synchronous)")
        ax.legend(loc="upper left")
    ax.set_ylabel("frequency (rad/s)")
    ax.set_title(f"{a['name']}: frequencies vs {name}" + (" (red: flutter, blue: divergence, orange: unconverged)"
                                                          if growth else ""), fontsize=9)
    if growth:
        axes[1, 0].plot(x, [float("nan") if g is None else g for g in growth], "o-", ms=3)
        axes[1, 0].axhline(0.0, color="0.6", lw=0.5)
        axes[1, 0].set_ylabel("growth rate max Re s (1/s)")
    axes[-1, 0].set_xlabel(figures.labelled(a, name))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("sweep", SCHEMA, run_sweep, needs, summary_lines, check=check, frees=frees, plot=plot))
