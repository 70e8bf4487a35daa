"""``symplectic``: a chain (separable H = sum v^2/(2m) + V(q)) run by a splitting method, the time loop in C.

A chain whose site kinetic energy is not m u'^2 / 2 with a constant m (or whose potential depends on a velocity)
is refused at ``integrator`` (exit 2; mechgen.runtime.core.splitting.require_separable): the splittings would
be silently wrong for it; simulate's ``method = "variational"`` serves any Lagrangian.

Scene keys: ``integrator`` (leapfrog | yoshida4 | yoshida6 | aba864: mechgen.runtime.core.splitting,
orders 2, 4, 6, 4), ``dt`` and ``t_end`` (required, model time units), ``stride`` (steps between outputs;
default 0: about 40 outputs per period T_1 = 2 pi / omega_1 of the lowest linear mode), ``initial_mode``
(1) and ``amplitude`` (1.0: the mode's largest displacement; fixed ends sin(n k pi/(N+1)), periodic ends
cos(2 pi k n / N)), ``modes`` (8: modal energies reported per output), ``loop`` (auto | c | numpy),
``max_steps`` (10^9, refused up front).

The steps run in C (mechgen/runtime/csrc/symplectic_loop.c) in chunks of ``stride`` steps; between
chunks the modal energies E_k = (P_k^2 + omega_k^2 Q_k^2)/2 come from a sine transform (fixed ends,
mechgen.runtime.linear.chain_modes; O(N log N) per output).

Outputs: ``energy_error`` (max |E(t) - E(0)| / |E(0)| over the outputs), ``steps_per_second`` (the loop's
steps over its wall time, transforms excluded), ``bytes_per_step`` (what the C loop's step streams, 8 N per array
read or written: per force call f zeroed, q in, f in and out (the kernel accumulates), per kick v, f (and the
inverse masses) in and v out, per drift q, v in and q out: 80 N for the leapfrog, 88 N with masses),
``bandwidth_share`` (bytes_per_step times steps_per_second over the bandwidth of a numpy copy of an N-array
split over every core at once, 16 N bytes over its best time of 5: the share of the machine's memory
bandwidth the one-thread loop reaches), ``bandwidth_fraction`` (deprecated, kept for scripts that read it:
the same with 64 N bytes per leapfrog step and a one-thread copy), ``loop`` (c or numpy), ``steps``; fixed ends also
``recurrence_periods`` and ``recurrence_fraction`` (the first return of the energy to mode 1, in periods
T_1, and the share of the harmonic energy back in it; null when none within t_end), ``t`` and
``mode_energies_series`` (rows of E_1..E_modes).
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from mechgen.analyses import schema, summary
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import REQUIRED, Option
from mechgen.errors import SceneError
from mechgen.runtime.core.splitting import METHODS, require_separable
from mechgen.scene.values import fail

STEP = "a number > 0 (or an expression)"
LOOPS = ("auto", "c", "numpy")
SCHEMA = {
    "integrator": Option(schema.one_of("integrator", tuple(METHODS)), "leapfrog", doc="the splitting: leapfrog, "
                         "yoshida4, yoshida6 or aba864 (orders 2, 4, 6, 4); a chain that is not separable is "
                         "refused here"),
    "dt": Option(schema.positive, REQUIRED, STEP, doc="the time step (the model's time unit)"),
    "t_end": Option(schema.positive, REQUIRED, STEP, doc="end time of the run (the model's time unit)"),
    "stride": Option(lambda ctx, key, value: schema.int_at_least(ctx, key, value, 0), 0,
                     doc="steps between outputs (0: about 40 outputs per period of the lowest linear mode)"),
    "initial_mode": Option(schema.count, 1, doc="the linear mode the chain starts in (1: the lowest)"),
    "amplitude": Option(schema.number, 1.0, doc="the initial mode's largest displacement (the coordinates' unit): "
                        "fixed ends sin(n k pi/(N+1)), periodic ends cos(2 pi k n / N)"),
    "modes": Option(schema.count, 8, doc="how many modal energies are reported per output"),
    "loop": Option(schema.one_of("loop", LOOPS), "auto", doc="where the steps run: auto, c or numpy"),
    "max_steps": Option(schema.count, 1_000_000_000, doc="the work budget in steps, refused up front"),
}


def check(ctx, base: str, options: dict) -> None:
    """dt <= t_end; t_end / dt within max_steps."""
    if options["dt"] > options["t_end"]:
        raise fail(ctx.file, f"{base}.dt", f"dt {options['dt']!r} exceeds t_end {options['t_end']!r}",
                   "a time step no larger than t_end")
    steps = int(round(options["t_end"] / options["dt"]))
    if steps > options["max_steps"]:
        raise fail(ctx.file, f"{base}.t_end", f"t_end / dt = {steps:,} steps exceeds max_steps = "
                   f"{options['max_steps']:,}", "a shorter t_end, a larger dt or a larger max_steps")


def needs(options: dict, *, internal: bool) -> set[str]:
    """The force, the energy (outputs) and the mass matrix (linear)."""
    return {"force", "outputs", "linear"}


def copy_bandwidth(n: int, repeats: int = 5) -> float:
    """Bytes per second of a numpy copy of n doubles (8 n read, 8 n written; the best of ``repeats``)."""
    src, dst = np.ones(n), np.empty(n)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        np.copyto(dst, src)
        best = min(best, time.perf_counter() - t0)
    return 16.0 * n / max(best, 1e-9)


def bytes_per_step(n: int, split) -> float:
    """Bytes one step moves as ``bandwidth_fraction`` counts them (kept for it): 16 n per force call, 24 n per kick
    and per drift (leapfrog: 64 n)."""
    kicks = _kicks(split)
    return 8.0 * n * (2 * split.forces_per_step + 3 * kicks + 3 * len(split.a))


def _kicks(split) -> int:
    """Kicks per step (a last kick merged with the next step's first)."""
    return sum(1 for b in split.b if b != 0.0) - (1 if split.b[0] != 0.0 and split.b[-1] != 0.0 else 0)


def loop_bytes_per_step(n: int, split, scaled: bool = False) -> float:
    """Bytes the C loop's step really moves (runtime/csrc/symplectic_loop.c), 8 n per array streamed:
    per force call f zeroed (8 n), q read (8 n) and f read and written by the accumulating kernel (16 n): 32 n; per
    kick v and f read, v written: 24 n (32 n with the inverse masses read, ``scaled``); per drift q and v read, q
    written: 24 n. Leapfrog: 80 n (88 n scaled)."""
    kick = 4 if scaled else 3
    return 8.0 * n * (4 * split.forces_per_step + kick * _kicks(split) + 3 * len(split.a))


def all_core_copy_bandwidth(n: int, repeats: int = 5, threads: int | None = None) -> float:
    """Bytes per second of a numpy copy of n doubles split over ``threads`` (default: every core) copying their
    parts at once (np.copyto releases the GIL; 16 n bytes over the best of ``repeats``): the memory system's bound
    with all cores, which a one-thread copy understates."""
    from concurrent.futures import ThreadPoolExecutor

    count = max(1, int(threads or os.cpu_count() or 1))
    src, dst = np.ones(n), np.empty(n)
    edges = np.linspace(0, n, count + 1).astype(int)
    parts = [(dst[a:b], src[a:b]) for a, b in zip(edges[:-1], edges[1:])]
    best = np.inf
    with ThreadPoolExecutor(count) as pool:
        for _ in range(repeats):
            t0 = time.perf_counter()
            list(pool.map(lambda part: np.copyto(*part), parts))
            best = min(best, time.perf_counter() - t0)
    return 16.0 * n / max(best, 1e-9)


def _start(system, options: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """(q0, v0, omega_1): the initial mode at its amplitude, and the lowest nonzero linear frequency."""
    from mechgen.runtime.linear.chain_modes import frequencies, mode_shape

    n, k = system.n, int(options.get("initial_mode", 1))
    if k > n:
        raise SceneError(f"initial_mode {k} exceeds the {n} sites", key="initial_mode",
                         expected=f"an integer from 1 to {n}")
    gamma = float(system.param_values().get("gamma", 1.0))
    if system.metadata.ends == "fixed":
        shape, omega1 = mode_shape(n, k), float(frequencies(n, gamma)[0])
    else:
        shape, omega1 = np.cos(2 * np.pi * k * np.arange(n) / n), 2 * np.sqrt(gamma) * np.sin(np.pi / n)
    q0 = float(options.get("amplitude", 1.0)) * shape / np.max(np.abs(shape))
    return q0, np.zeros(n), omega1


def run_symplectic(system, options: dict, context: dict) -> dict:
    """Run the splitting method; report energy error, speed, bandwidth share and (fixed ends) the recurrence."""
    from mechgen.analyses.simulate import leapfrog_masses
    from mechgen.runtime.core.splitting import method
    from mechgen.runtime.core.symplectic_c import evolve_system
    from mechgen.runtime.linear.chain_modes import modal_energies, recurrence

    if not system.is_lattice:
        raise SceneError(f"model {system.metadata.model} is not a chain", key="kind",
                         expected="a chain model (Model.chain) for the symplectic kind")
    require_separable(system, "integrator", f"integrator '{options.get('integrator', 'leapfrog')}'",
                      "kind = 'simulate' with method = 'variational' (any kinetic energy), or an implicit method")
    split = method(options.get("integrator", "leapfrog"))
    dt, t_end = float(options["dt"]), float(options["t_end"])
    steps = int(round(t_end / dt))
    q, v, omega1 = _start(system, options)
    minv = leapfrog_masses(system, system.linear(np.zeros(system.n))["M"])
    unit = bool(np.all(minv == 1.0))
    stride = int(options.get("stride", 0)) or max(1, int(round(2 * np.pi / omega1 / 40 / dt)))
    stride = min(stride, steps)
    fixed = system.metadata.ends == "fixed"
    count = min(int(options.get("modes", 8)), system.n)
    gamma = float(system.param_values().get("gamma", 1.0))
    ts, energies, modal = [0.0], [system.outputs(q, v)["energy"]], []
    full = [modal_energies(q, v, gamma)] if fixed else []
    spent, done, used = 0.0, 0, "c"
    while done < steps:
        chunk = min(stride, steps - done)
        t0 = time.perf_counter()
        q, v, e, used = evolve_system(system, q, v, dt, chunk, split, minv=None if unit else minv, stride=chunk,
                                      loop=options.get("loop", "auto"))
        spent += time.perf_counter() - t0
        done += chunk
        ts.append(done * dt)
        energies.append(float(e[-1]))
        if fixed:
            full.append(modal_energies(q, v, gamma))
    e = np.asarray(energies)
    rate = steps / max(spent, 1e-12)
    out = {"energy_error": float(np.max(np.abs(e - e[0])) / max(abs(e[0]), 1e-300)), "steps_per_second": rate,
           "bandwidth_fraction": bytes_per_step(system.n, split) / copy_bandwidth(system.n) * rate,
           "bytes_per_step": loop_bytes_per_step(system.n, split, scaled=not unit),
           "bandwidth_share": loop_bytes_per_step(system.n, split, scaled=not unit) * rate
           / all_core_copy_bandwidth(system.n),
           "loop": used, "steps": steps, "integrator": split.name}
    if fixed:
        E = np.asarray(full)
        rec = recurrence(np.asarray(ts), E, omega1)
        out["recurrence_periods"] = rec.periods if rec.found else None
        out["recurrence_fraction"] = rec.fraction if rec.found else None
        modal = E[:, :count]
        out["t"] = [float(t) for t in ts]
        out["mode_energies_series"] = [[float(x) for x in row] for row in modal]
    return out


def plot(plt, a: dict, path: Path) -> list[Path]:
    """E_k(t) of the first modes (fixed ends), time in periods of mode 1 when a recurrence was found."""
    out = a["outputs"]
    if "mode_energies_series" not in out:
        return []
    fig, ax = plt.subplots(figsize=(7, 4))
    E = np.asarray(out["mode_energies_series"])
    for k in range(E.shape[1]):
        ax.plot(out["t"], E[:, k], lw=1, label=f"E_{k + 1}")
    ax.set_xlabel("t")
    ax.set_ylabel("modal energy E_k")
    ax.legend(fontsize=7, ncol=2)
    title = a["name"]
    if out.get("recurrence_periods") is not None:
        title += f": recurrence at {out['recurrence_periods']:.2f} T_1, {100 * out['recurrence_fraction']:.2f} %"
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


def summary_lines(outputs: dict) -> list[str]:
    """Every output but the series."""
    return summary.output_lines(outputs, skip=("t", "mode_energies_series"))


register(AnalysisKind("symplectic", SCHEMA, run_symplectic, needs, summary_lines, check=check, plot=plot,
                      sweepable=True))
