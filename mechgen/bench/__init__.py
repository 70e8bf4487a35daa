"""``mechgen bench``: the benchmark suites and their registry.

One module per suite (``mechgen.bench.<module>``, each with its entry point ``run_<...>_benchmarks(out=...,
quick=...)`` writing its reports into ``out``), the helpers they share in :mod:`mechgen.bench.common`.
A suite is added by writing its module and one :class:`Suite` line in :data:`REGISTRY`; ``mechgen bench
--list`` names them. Importing this package loads no suite (and neither numpy nor sympy).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Suite:
    """A benchmark suite: its name on the command line, the module and function that run it, what it measures
    and the reports it writes into the output folder."""

    name: str
    module: str
    function: str
    summary: str
    writes: tuple[str, ...] = ()
    #: the other tools the suite times against (packages are optional extras; hand-written baselines live in
    #: benchmarks/)
    peers: tuple[str, ...] = ()
    #: whether the suite writes the harness's standard reports (common.suite_report)
    standard: bool = True

    @property
    def reports(self) -> tuple[str, ...]:
        """Every file the suite writes: the standard three, then its own."""
        own = tuple(f"{self.name}_{tail}" for tail in ("work_precision.csv", "work_precision.png", "ratios.json"))
        return (own if self.standard else ()) + tuple(w for w in self.writes if w not in own)

    def run(self, out: Path, quick: bool = False) -> dict:
        """Run the suite (importing its module now) and return its results."""
        return getattr(importlib.import_module(self.module), self.function)(out=Path(out), quick=quick)


#: the suites, in the order ``mechgen bench`` runs them
REGISTRY: dict[str, Suite] = {s.name: s for s in (
    Suite("fpu", "mechgen.bench.fpu", "run_fpu_benchmarks",
          "FPU chain kernels: generated C against hand C, numpy, sympy.lambdify, CasADi; call overhead, build and "
          "scene start times", ("fpu_kernels.csv", "fpu_kernels.json", "fpu_kernels.md"),
          peers=("hand-written C", "numpy", "sympy.lambdify", "CasADi"), standard=False),
    Suite("beam", "mechgen.bench.beam", "run_field_benchmarks",
          "clamped-free beam: work against precision of four discretisations, assembly against scikit-fem; the "
          "continua scenes unpinned against pinned",
          ("beam_work_precision.csv", "beam_work_precision.md", "beam_work_precision.png", "beam_assembly.json",
           "beam_assembly.md", "beam_user_path.json", "beam_user_path.md"), peers=("scikit-fem",)),
    Suite("rotor", "mechgen.bench.rotor", "run_rotor_benchmarks",
          "Campbell diagrams of ROSS's example rotor, mechgen against ROSS, pinned and as a user runs both", ("rotor_campbell.json",
                                                                              "rotor_campbell.md"), peers=("ROSS",)),
    Suite("balloon", "mechgen.bench.balloon", "run_balloon_benchmarks",
          "the ballooning string's branch with stability against a hand-written scipy baseline",
          ("balloon_branch.json", "balloon_branch.md"), peers=("hand-written scipy shooting (benchmarks/)",)),
    Suite("startup", "mechgen.bench.startup", "run_startup_benchmarks",
          "whole-process start of a cached scene (laval_rotor, beam_modes): median wall time and import share, "
          "unpinned against pinned",
          ("startup.json", "startup.md"), standard=False),
    Suite("impacts", "mechgen.bench.impacts", "run_impact_benchmarks",
          "restitution over 200 damping ratios for five contact laws against hand-written solve_ivp with events; "
          "work-precision per law and integrator", ("impacts.json", "impacts.md", "impacts.csv",
                                                    "impacts_work_precision.png"),
          peers=("hand-written solve_ivp with events (benchmarks/)",)),
    Suite("friction", "mechgen.bench.friction", "run_friction_benchmarks",
          "rate-and-state spring-slider against hand-written solve_ivp Radau at equal accuracy; work-precision of "
          "the velocity step and of the stick-slip hysteresis energy per integrator", ("friction.json", "friction.md", "friction.csv",
                                                        "friction_work_precision.png"),
          peers=("hand-written solve_ivp Radau (benchmarks/)",)),
    Suite("rods", "mechgen.bench.rods", "run_rods_benchmarks",
          "Cosserat cantilever: static tip-load work-precision (collocation, shooting) against the elastica and "
          "PyElastica's damped static limit; dynamic tip trajectory and a stiff rod against PyElastica",
          ("rods.json", "rods.md", "rods_dynamic_work_precision.csv", "rods_dynamic_work_precision.png"),
          peers=("PyElastica",)),
    Suite("threads", "mechgen.bench.threads", "run_threads_benchmarks",
          "every shipped scene as a whole process, default environment against one BLAS thread (unpinned / pinned)",
          ("threads.json", "threads.md"), standard=False),
    Suite("simulate", "mechgen.bench.simulate", "run_simulate_benchmarks",
          "a forced Duffing oscillator's time response: the compiled loop against scipy's stepper on the same "
          "kernels and a hand-written solve_ivp; a 10^3-point sweep of simulate", ("simulate.json", "simulate.md"),
          peers=("scipy DOP853 stepped in Python", "hand-written solve_ivp")),
    Suite("orbits", "mechgen.bench.orbits", "run_orbit_benchmarks",
          "a Duffing frequency-response curve through its folds by harmonic balance and shooting against a "
          "hand-written scipy shooting-plus-continuation baseline, at equal fold accuracy", ("orbits.json", "orbits.md"),
          peers=("hand-written scipy shooting + continuation (benchmarks/)",)),
    Suite("sweep", "mechgen.bench.sweep", "run_sweep_benchmarks",
          "a 10^4-point Laval rotor stability sweep on the serial, local-process and Dask executors (2 workers): wall "
          "time, overhead per point, dask / processes", ("sweep.json", "sweep.md"),
          peers=("local processes (concurrent.futures)", "dask.distributed LocalCluster")),
    Suite("multibody", "mechgen.bench.multibody", "run_multibody_benchmarks",
          "n-link pendulums (n = 2 ... 64) and a 10 x 10 mass-spring lattice: first and cached build, right-hand "
          "side per call, a 10 s DOP853 simulation and the accelerations' agreement, mechgen (flow only, every "
          "kernel) against PyDy", ("multibody_results.csv", "multibody_results.json", "multibody_results.md",
                                  "multibody_ratios.json", "multibody_build_time.png"),
          peers=("PyDy Kane + lambdify", "PyDy Kane + cython", "PyDy/sympy Lagrange + lambdify"), standard=False),
    Suite("plane", "mechgen.bench.plane", "run_plane_benchmarks",
          "plane-stress elasticity stiffness (P1, P2 triangles, ~1e5 and ~1e6 unknowns) assembled on the same mesh, "
          "checked equal, median of interleaved repeats; a compiled plane model's tangent() as a user runs it", ("plane_assembly.json", "plane_assembly.md"),
          peers=("scikit-fem",)),
)}

#: the suite names (``mechgen bench`` with none runs them all)
SUITES = tuple(REGISTRY)


def suite_lines() -> list[str]:
    """One line per suite: its name, what it measures and the reports it writes (``mechgen bench --list``)."""
    width = max(len(name) for name in REGISTRY)
    return [f"{s.name:{width}s}  {s.summary}" + (f"; peers: {', '.join(s.peers)}" if s.peers else "")
            + (f" -> {', '.join(s.reports)}" if s.reports else "") for s in REGISTRY.values()]


def run_benchmarks(models_: list[str] | None = None, *, out: Path, quick: bool = False) -> dict:
    """Run the benchmark suites named in ``models_`` (default: all of :data:`SUITES`), in registry order.

    ``fpu``: FPU chain kernels, writes ``out/fpu_kernels.{csv,json,md}``; ``beam``: the continua
    work-precision and assembly study (:mod:`mechgen.bench.beam`); ``rotor``: Campbell diagrams against ROSS
    (:mod:`mechgen.bench.rotor`); ``balloon``: the ballooning string's branch with stability against a
    hand-written scipy baseline (:mod:`mechgen.bench.balloon`); ``startup``: whole-process start of cached
    scenes (:mod:`mechgen.bench.startup`); ``threads``: every shipped scene unpinned against pinned
    (:mod:`mechgen.bench.threads`); ``sweep``: a Laval rotor sweep on each executor (:mod:`mechgen.bench.sweep`). Every suite also times its scenes as a user runs them (default
    environment) beside its pinned figures. Returns {suite: its results}.
    """
    from mechgen.errors import InputError

    chosen = list(models_ or SUITES)
    unknown = [m for m in chosen if m not in REGISTRY]
    if unknown:
        raise InputError(f"unknown benchmark {unknown[0]!r}", key="bench", expected=f"one of {', '.join(SUITES)}")
    return {name: suite.run(out, quick=quick) for name, suite in REGISTRY.items() if name in chosen}


def __getattr__(name: str):
    """The FPU suite's public names, as ``mechgen.bench`` gave them before the suites had modules of their own
    (``best_time``, ``run_fpu_benchmarks``, ``kernel_rows`` ...): loaded on first use."""
    if name.startswith("_"):
        raise AttributeError(f"module 'mechgen.bench' has no attribute {name!r}")
    fpu = importlib.import_module("mechgen.bench.fpu")
    try:
        return getattr(fpu, name)
    except AttributeError:
        raise AttributeError(f"module 'mechgen.bench' has no attribute {name!r}") from None
