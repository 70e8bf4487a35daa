"""Run one function over a list of parameter points: serially, in local processes, or on Dask.

Order is preserved; a tqdm progress bar with the remaining time goes to stderr when it is a
terminal and the sweep lasts over 2 s (mechgen.runtime.core.budget.Progress). A
:class:`~mechgen.runtime.core.budget.Budget` bounds the wall time: after each point (or chunk) the
time for all of them is estimated from the points done (elapsed * total / done) and the sweep is
refused as soon as that estimate, trusted after 2 s, exceeds the budget; an inner analysis's spent
budget is re-raised with the point and its key under ``inner`` (``analysis.max_steps``).

A point whose function fails is, with ``on_error = "record"``, recorded (its result None, its
status ``"failed: <message>"``) and the sweep goes on; a user's mistake (an
:class:`~mechgen.errors.InputError`) and a spent budget still stop the sweep, and so does a sweep
none of whose points succeeded (the first failure, naming its point). With ``on_error = "raise"``
the first failure stops the sweep, naming the point.

Executors (:class:`SweepExecutor`): ``serial``; ``processes`` (``workers`` local processes, BLAS on
one thread each); ``dask`` (mechgen.runtime.core.dask_sweep: chunks of points on a
``dask.distributed`` cluster). Each point's result depends only on the point: the executors give the
same numbers (tests/test_sweep_executors.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from mechgen.errors import InputError
from mechgen.runtime.core.budget import Budget, BudgetExceeded, Progress
from mechgen.runtime.core.sweep_tasks import (OK, SCHEDULER_FORM, SweepError, describe, guarded, inner_budget,
                                              scheduler_address)
from mechgen.runtime.core.threads import single_thread_worker

EXECUTORS = ("serial", "processes", "dask")
ON_ERROR = ("record", "raise")
@dataclass(frozen=True)
class SweepExecutor:
    """Where the points run: ``kind`` (serial | processes | dask), ``workers`` (processes, or Dask
    workers of a LocalCluster started for the run; 0: two), ``scheduler`` (a running Dask
    scheduler's address, ``tcp://host:port``; None: a LocalCluster on the loopback for this sweep),
    ``chunk_seconds`` (the work a Dask task carries at least, from a warm point's time: Dask's
    per-task overhead is 0.2-1 ms)."""

    kind: str = "serial"
    workers: int = 0
    scheduler: str | None = None
    chunk_seconds: float = 0.5

    def __post_init__(self) -> None:
        if self.kind not in EXECUTORS:
            raise InputError(f"unknown executor {self.kind!r}", key="executor", expected=" | ".join(EXECUTORS))
        if self.scheduler is not None:
            try:
                scheduler_address(self.scheduler)
            except ValueError as exc:
                raise InputError(f"{str(self.scheduler)[:80]!r} is not a scheduler address: {exc}", key="scheduler",
                                 expected=SCHEDULER_FORM) from None

    @classmethod
    def of(cls, kind: str | None, workers: int = 0, scheduler: str | None = None) -> "SweepExecutor":
        """The executor a sweep's keys name; no ``executor`` key: processes when ``workers`` > 1, else serial."""
        if kind is None:
            kind = "processes" if workers > 1 else "serial"
        return cls(kind, int(workers), scheduler)


@dataclass
class SweepRun:
    """A sweep's outcome: ``results[i]`` (None where point i failed), ``status[i]`` (``"ok"`` or
    ``"failed: ..."``), ``retried`` (indices of points run again after their worker was lost),
    ``tasks`` (the tasks the executor ran: points, or Dask chunks)."""

    results: list
    status: list
    retried: list = field(default_factory=list)
    tasks: int = 0


def sweep(func, points: list, *, workers: int = 0, progress: bool = True, desc: str = "sweep",
          budget: Budget | None = None, inner: str = "analysis", labels=None) -> list:
    """[func(point) for point in points], with ``workers`` > 1 local processes, under ``budget``; ``labels[i]``
    names point i in messages (default: the point, or the last dict of a task tuple). The first failure stops
    the sweep (SweepError naming the point)."""
    run = sweep_points(func, points, executor=SweepExecutor.of(None, workers), progress=progress, desc=desc,
                       budget=budget, inner=inner, labels=labels, on_error="raise")
    return run.results


def sweep_points(func, points, *, executor: SweepExecutor | None = None, progress: bool = True,
                 desc: str = "sweep", budget: Budget | None = None, inner: str = "analysis", labels=None,
                 on_error: str = "record") -> SweepRun:
    """``func`` at every point on ``executor`` (module docstring): a :class:`SweepRun` in point order."""
    executor = executor or SweepExecutor()
    if on_error not in ON_ERROR:
        raise InputError(f"unknown on_error {on_error!r}", key="on_error", expected=" | ".join(ON_ERROR))
    record = on_error == "record"
    total = len(points)
    run = SweepRun([None] * total, [None] * total)

    def label(i: int):
        return labels[i] if labels is not None else points[i]

    def store(i: int, outcome: tuple) -> None:
        """Keep point i's (status, value), or raise its failure (on_error = raise)."""
        run.status[i], run.results[i] = outcome

    with Progress(total, desc=desc, unit="point", enabled=progress) as bar:
        finished = 0

        def done(count: int) -> None:
            nonlocal finished
            finished += count
            bar.update(count)
            if budget is not None:
                budget.project(finished, total, lambda: f"{finished:,} of {total:,} points")

        if executor.kind == "dask":
            from mechgen.runtime.core.dask_sweep import run_on_dask

            run.retried, run.tasks = run_on_dask(func, points, executor, store, done, label, inner, record)
        elif executor.kind == "processes" and executor.workers > 1:
            _run_processes(func, points, executor.workers, store, done, label, inner, record)
            run.tasks = total
        else:
            for i in range(total):
                store(i, guarded(func, points[i], inner, label(i), record))
                done(1)
            run.tasks = total
    if total and all(s != OK for s in run.status):
        first = run.status[0][len("failed: "):]
        raise SweepError(f"every sweep point failed; the first, {describe(label(0))}: {first}")
    return run


#: the tasks of the sweep now running on forked workers (they inherit it: a task need not pickle)
_INHERITED: dict = {}


def inherited_point(i: int, inner: str, record: bool) -> tuple:
    """Point i of the sweep the worker inherited at its fork (:func:`guarded` on it)."""
    func, points = _INHERITED["tasks"]
    return guarded(func, points[i], inner, None, record)


def _run_processes(func, points, workers: int, store, done, label, inner: str, record: bool) -> None:
    """The points on ``workers`` local processes. Where the platform forks (Linux, macOS), the workers inherit
    the tasks and receive only their indices, so a task holding a compiled system (a sweep called from Python)
    need not pickle; elsewhere each task is pickled to its worker."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    forks = "fork" in mp.get_all_start_methods()
    context = mp.get_context("fork") if forks else None
    if forks:
        _INHERITED["tasks"] = (func, points)
    pool = ProcessPoolExecutor(max_workers=workers, initializer=single_thread_worker, mp_context=context)
    try:
        futures = [pool.submit(inherited_point, i, inner, record) if forks
                   else pool.submit(guarded, func, points[i], inner, None, record) for i in range(len(points))]
        for i, fut in enumerate(futures):
            failure = fut.exception()  # waits for point i; the sweep's own budget (a timer here) interrupts the wait
            if isinstance(failure, BudgetExceeded):  # the point's budget, spent in the worker
                raise inner_budget(failure, label(i), inner) from failure
            if isinstance(failure, SweepError):  # raised in the worker, which knew the task, not its label
                raise SweepError(f"sweep point {describe(label(i))} failed: {failure}") from failure
            store(i, fut.result())
            done(1)
    except BaseException:  # a failure, a spent budget (the parent's backstop included), Ctrl-C: end the workers now
        stop_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        _INHERITED.pop("tasks", None)


def stop_workers(pool) -> None:
    """Terminate (SIGTERM) the worker processes of a ProcessPoolExecutor, so that its shutdown does not wait for the
    points they are still running (a sweep stopped by its budget would otherwise run on until they end). The pool
    keeps its processes in its ``_processes`` mapping (CPython 3.9-3.13; 3.14 has ``terminate_workers``)."""
    terminate = getattr(pool, "terminate_workers", None)
    if terminate is not None:
        terminate()
        return
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        if process.is_alive():
            process.terminate()
