"""``campbell``: a Campbell diagram, the damped modes over a range of one parameter (the spin speed).

The modes are tracked across speeds (mechgen.runtime.linear.campbell) and critical speeds are found where a
whirl frequency crosses a multiple of the speed. Scene keys: ``over`` (one numeric parameter with two
or more increasing values), ``count`` (modes; left out: min(8, the system's degrees of freedom), a count written larger than
that is refused), ``multiples`` (of the speed, default [1]),
``method`` (auto, exact, reduced), ``about`` and ``at`` (the operating point), ``max_seconds`` (the wall-time
budget, default 600 s: the exact path refuses once its first speeds project past it; exit 1), and where the
per-speed eigen-solves run, as for ``sweep``: ``executor`` (``serial``, ``processes`` or ``dask``; left out:
processes when ``workers`` > 1, else serial), ``workers``, ``scheduler`` (Python calls only: a running scheduler's
address; a scene cannot name one, ``mechgen run --scheduler`` does).
On a parallel executor every speed is solved exactly (full size; the speeds are independent: their
matrices are assembled here, the solves are distributed, in Dask chunks of at least ~0.5 s of work) and the
modes are tracked here afterwards, so the result is the serial exact one; ``method = "reduced"`` (whose basis
grows from speed to speed) is refused there, and ``auto`` means exact. Outputs: ``speeds``, ``frequencies`` and
``whirl`` (forward, backward, linear for a straight-line orbit at that speed, none for a mode that leaves the
whirl stations at rest: mechgen.analyses.whirl) and ``log_dec`` (one row per speed), ``critical_speeds``, ``parameter``, ``method``, ``exact_solves``
and ``executor``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from mechgen.analyses import schema, summary
from mechgen.analyses.context import scheduler_of
from mechgen.analyses.operating_point import operating_point
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, REQUIRED, Option
from mechgen.analyses.whirl import SPARSE_N, whirl_stations
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.core.sweep import SweepExecutor
from mechgen.runtime.linear.campbell import CampbellOptions, campbell, critical_speeds, fit_speed_polynomial
from mechgen.scene.values import fail, is_choice, join, param_info, type_name


def _speeds(ctx, key: str, value: object) -> dict[str, list]:
    """A campbell range: one numeric parameter (the spin speed) with increasing values."""
    over = schema.over(ctx, key, value)
    if len(over) != 1:
        raise fail(ctx.file, key, f"a campbell diagram runs over one parameter, got {len(over)}",
                   "one entry: Omega = {start, stop, num} or an array")
    (name, values), = over.items()
    if is_choice(param_info(ctx.file, key, ctx.model, name)) or len(values) < 2 or np.any(np.diff(values) <= 0):
        raise fail(ctx.file, join(key, name), "campbell speeds must be two or more increasing numbers",
                   "increasing numbers, e.g. {start = 0, stop = 1000, num = 50}")
    return over


def _multiples(ctx, key: str, value: object) -> list[float]:
    if not isinstance(value, list) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a non-empty array of positive numbers")
    return [schema.positive(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]


SCHEMA = {"over": Option(_speeds, REQUIRED, "a table: parameter = [values] or {start, stop, num}",
                         doc="one numeric parameter (the spin speed, its unit) with two or more increasing "
                         "values"),
          "count": Option(schema.count, doc="how many modes to track (left out: min(8, the degrees of freedom); "
                           "a larger count is refused)"),
          "multiples": Option(_multiples, [1.0], doc="the multiples of the speed whose crossings with a whirl "
                              "frequency are critical speeds"),
          "method": Option(schema.one_of("campbell method", ("auto", "exact", "reduced")),
                           doc="the eigen-solves: auto, exact (full size at every speed) or reduced (a basis "
                           "grown from speed to speed, serial executor only)"),
          "about": Option(schema.about, doc="the name of an earlier steady analysis whose state is the operating "
                          "point"),
          "at": Option(schema.coordinate_table, doc="the operating point's coordinates (a table coordinate = "
                       "value; left out: zero)"),
          "max_seconds": Option(schema.positive, ABSENT, doc="the wall-time budget (s, default 600): the exact "
                                "path refuses once its first speeds project past it"),
          **schema.executor_options()}


def _executor(options: dict, context: dict | None = None) -> SweepExecutor:
    return SweepExecutor.of(options.get("executor"), options.get("workers", 0), scheduler_of(options, context or {}))


def check(ctx, base: str, options: dict) -> None:
    """A ``scheduler`` needs ``executor = "dask"``; ``method = "reduced"`` runs serially only."""
    schema.check_executor(ctx, base, options)
    kind = _executor(options).kind
    if options.get("method") == "reduced" and kind != "serial":
        key = join(base, "executor" if "executor" in options else "workers")
        raise fail(ctx.file, key, f"method = \"reduced\" carries its reduced basis from speed to speed and cannot "
                   f"run on the {kind} executor",
                   "executor = \"serial\" with method = \"reduced\", or method = \"exact\" (or \"auto\", which "
                   "solves every speed exactly on a parallel executor)")


def needs(options: dict, *, internal: bool) -> set[str]:
    """M, D, G, K: the linear kernel."""
    return {"linear"}


def frees(options: dict) -> list[str]:
    """The speed parameter: free in the kernels."""
    return list(options["over"])


def _speed_parameter(system, options: dict) -> tuple[str, list[float]]:
    (name, values), = options["over"].items()
    if name not in system.metadata.params:
        raise SceneError(f"campbell over {name!r}, which the compiled kernels fold as a constant",
                         key="over", expected="a numeric model parameter (kept free by the scene)")
    return name, [float(v) for v in values]


#: the number of tracked modes when the scene does not say (fewer when the system has fewer)
DEFAULT_COUNT = 8


def _count(system, options: dict) -> int:
    """The modes to track: ``count`` as written (at most the degrees of freedom), else min(DEFAULT_COUNT, n)."""
    n = int(system.n)
    if "count" not in options:
        return min(DEFAULT_COUNT, n)
    count = int(options["count"])
    if count > n:
        raise SceneError(f"count = {count} asks for more modes than the {n} a system of {n} degrees of freedom has",
                         key="count", expected=f"at most {n}, or no count (the default is min({DEFAULT_COUNT}, {n}))")
    return count


def run_campbell(system, options: dict, context: dict) -> dict:
    """Campbell diagram: tracked damped frequencies over the speed range, whirl, log_dec, critical speeds.

    With more than four speeds the matrices are tested for a polynomial dependence on the speed
    (fit_speed_polynomial: three or four assemblies); when it holds, no further assembly is needed and
    the Campbell runs on the reduced basis (mechgen.runtime.linear.campbell), else it assembles at every speed.
    ``options['method'] = 'exact'`` forces full-size solves at every speed."""
    name, speeds = _speed_parameter(system, options)
    if not system.metadata.whirl:
        raise SceneError(f"model {system.metadata.model} declares no whirl pair", key="kind",
                         expected="a model with Model.whirl_pair (a rotor) for a campbell analysis")
    stations = whirl_stations(system)
    if stations is None:
        raise SceneError("a campbell diagram tracks whirl at nodal values; substructures joined by multipliers have "
                         "none", key="joints", expected="joints = 'assembly' for campbell (the same frequencies)")
    q = operating_point(system, options, context)

    def assembled(speed: float) -> dict:
        mats = system.with_params(**{name: speed}).linear(q)
        return {"M": mats["M"], "D": mats["D"], "G": mats["G"], "K": mats["K"]}

    def assembled_at(speed: float) -> dict:
        mats = assembled(speed)
        return {"M": mats["M"], "C": mats["D"] + mats["G"], "K": mats["K"]}

    count = _count(system, options)
    sparse = system.n > SPARSE_N
    # matrices polynomial in the speed (a rotor's G = Omega G1): four assemblies, then sparse adds
    poly = fit_speed_polynomial(assembled, speeds[0], speeds[-1]) if len(speeds) > 4 else None
    matrices_at = assembled_at if poly is None else poly.combined({"M": ("M",), "C": ("D", "G"), "K": ("K",)})
    budget = Budget(f"campbell over {name}", unit="speeds",
                    seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    executor = _executor(options, context)
    res = campbell(matrices_at, speeds, count, CampbellOptions(sparse=sparse, method=options.get("method", "auto"),
                                                                budget=budget, executor=executor),
                   x_index=stations[0], y_index=stations[1])
    crit = critical_speeds(res, options.get("multiples", [1.0]), refine=matrices_at, sparse=sparse)
    freqs = np.asarray(res.frequencies)
    return {"speeds": [float(w) for w in res.speeds], "frequencies": [[float(f) for f in row] for row in freqs],
            "whirl": [list(row) for row in res.whirl], "log_dec": [[float(d) for d in row] for row in res.log_dec],
            "critical_speeds": [{"mode": int(c["mode"]) + 1, "multiple": float(c["multiple"]),
                                 "speed": float(c["speed"]), "frequency": float(c["frequency"]), "whirl": c["whirl"]}
                                for c in crit],
            "parameter": name, "method": res.method, "exact_solves": int(res.exact_solves), "executor": executor.kind}


def summary_lines(outputs: dict) -> list[str]:
    """The default lines without the per-speed eigenvalues and log decrements."""
    return summary.output_lines(outputs, skip=("eigenvalues", "log_dec"))


#: line styles of the whirl labels in the Campbell plot
STYLES = {"forward": "-", "backward": "--", "linear": "-.", "none": ":"}


def plot(plt, a: dict, path: Path) -> list[Path]:
    """Tracked whirl frequencies against spin speed (forward solid, backward dashed, linear dash-dotted,
    none dotted: the label at the middle speed), multiples of the speed as excitation lines and the critical
    speeds where they cross."""
    out = a["outputs"]
    speeds, freqs = out["speeds"], list(zip(*out["frequencies"]))
    whirls = list(zip(*out["whirl"]))
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for k, (curve, labels) in enumerate(zip(freqs, whirls)):
        label = labels[len(labels) // 2]
        ax.plot(speeds, curve, STYLES.get(label, ":"), color=f"C{k % 10}", lw=1.2,
                label=f"mode {k + 1} ({label[0].upper()})")
    top = max(max(c) for c in freqs)
    for r in sorted({c["multiple"] for c in out.get("critical_speeds", [])} or {1.0}):
        reach = min(speeds[-1], top / r)
        ax.plot([0, reach], [0, r * reach], "k:", lw=1)
        ax.annotate(f"{r:g}x", (reach, r * reach), fontsize=7)
    for c in out.get("critical_speeds", []):
        ax.plot(c["speed"], c["frequency"], "kx", ms=6)
    ax.set_xlabel(f"{out.get('parameter', 'speed')} (rad/s)")
    ax.set_ylabel("damped natural frequency (rad/s)")
    ax.set_title(f"{a['name']}: Campbell diagram\n(solid forward, dashed backward, dash-dot linear; "
                 f"x critical speeds)", fontsize=9)
    ax.legend(fontsize=7, ncol=2, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("campbell", SCHEMA, run_campbell, needs, summary_lines, check=check, frees=frees, plot=plot))
