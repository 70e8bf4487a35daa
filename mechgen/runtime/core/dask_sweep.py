"""A sweep's points on a ``dask.distributed`` cluster, in chunks, with lost workers' points run again.

- **Cluster**: a running scheduler the user named (``SweepExecutor.scheduler = "tcp://host:port"``, from
  ``mechgen run --scheduler`` or a Python argument, never from a scene), else the one in Dask's own
  ``scheduler-address`` setting (``DASK_SCHEDULER_ADDRESS``), else a ``LocalCluster`` on the loopback started
  for this sweep and closed after it (``workers`` worker processes, default 2, one thread each, no dashboard).
  Every address is checked (:func:`mechgen.runtime.core.sweep.scheduler_address`) before anything connects.
  A scheduler and its workers run code in this process (results are unpickled): only the user names one.
- **Chunks**: the first two points run here (the first also puts the compiled kernels in the compile
  cache, where the workers find them: a task carries the compile request, never a shared library, and
  warms this process: imports, kernels loaded) and the second one's time t1 sizes the chunks:
  c = ceil(chunk_seconds / t1) points, at most ceil((n - 2) / workers) so that every worker gets work. Dask's overhead is 0.2-1 ms per task, so a chunk of >= 0.5 s costs
  under 0.2 %.
- **Submission**: ``pure=False`` (two chunks with equal points are still two tasks), at most
  4 chunks per worker in flight (a grid of 10^6 points is not held by the scheduler at once);
  results stream back in completion order (``as_completed``) into their grid places, with the
  progress bar.
- **Faults**: each chunk logs its start as a scheduler event (topic :data:`TOPIC`, with the sweep's id,
  the chunk, the worker and its pid). When a worker dies, Dask runs its chunks again elsewhere
  (up to ``distributed.scheduler.allowed-failures`` times); a chunk started more than once has its
  points reported in ``retried``. A chunk that Dask gives up on (KilledWorker) is submitted again
  by us, up to :data:`RESUBMITS` times. Each point is still run exactly once in the results.
"""
from __future__ import annotations

import itertools
import math
import os
import time
import uuid
from collections import Counter

from mechgen.errors import InputError
from mechgen.runtime.core.budget import BudgetExceeded
from mechgen.runtime.core.sweep_tasks import OK, SweepError, describe, guarded, inner_budget
from mechgen.runtime.core.threads import single_thread_worker

#: the scheduler event topic chunk starts are logged under
TOPIC = "mechgen-sweep"
#: chunks in flight per worker
IN_FLIGHT = 4
#: our own resubmissions of a chunk Dask gave up on
RESUBMITS = 2
#: points run here before the cluster starts: the first warms this process, the last one's time sizes the chunks
WARM_POINTS = 2
#: seconds to wait for a scheduler to answer and for its first worker
CONNECT_SECONDS = 10.0


def run_chunk(func, tasks: list, sweep_id: str, index: int, inner: str) -> tuple[int, list]:
    """On a worker: log the chunk's start, then (status, result) of every task (mechgen.runtime.core.sweep.guarded:
    failures recorded; the driver raises the first with on_error = raise).

    BLAS runs on one thread (the worker's one thread is its share of the machine)."""
    from distributed import get_worker

    single_thread_worker()
    worker = get_worker()
    worker.log_event(TOPIC, {"sweep": sweep_id, "chunk": index, "worker": worker.address, "pid": os.getpid()})
    return index, [guarded(func, task, inner, None, True) for task in tasks]


def chunk_size(first_seconds: float, remaining: int, workers: int, chunk_seconds: float) -> int:
    """Points per task: enough for ``chunk_seconds`` of work at ``first_seconds`` a point, at most
    ceil(remaining / workers) (every worker gets a chunk), at least 1."""
    wanted = math.ceil(chunk_seconds / max(first_seconds, 1e-6))
    return max(1, min(wanted, math.ceil(remaining / max(workers, 1))))


def run_on_dask(func, points, executor, store, done, label, inner: str, record: bool) -> tuple[list, int]:
    """Run ``func`` over ``points`` on Dask (module docstring); ``store(i, (status, result))`` keeps each
    point, ``done(k)`` counts k finished points. Returns (retried point indices, tasks submitted)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:  # the extra is missing
        raise InputError("executor = 'dask' needs dask.distributed", key="executor",
                         expected="pip install 'mechgen[dask]', or executor = 'serial' | 'processes'") from exc
    total = len(points)
    if total == 0:
        return [], 0
    address = executor.scheduler if executor.scheduler is not None else configured_scheduler()
    # the first point warms this process (imports, kernels loaded from the cache): the second one's time is the
    # time of a point (a first point of 30 ms beside 0.3 ms ones would cut 10^4 points into 600 tasks)
    here = min(total, WARM_POINTS)
    for i in range(here):
        started = time.perf_counter()
        store(i, guarded(func, points[i], inner, label(i), record))
        first = time.perf_counter() - started
        done(1)
    if total == here:
        return [], here
    cluster = None
    try:
        if address is None:
            cluster = LocalCluster(n_workers=executor.workers or 2, threads_per_worker=1, processes=True,
                                   host="127.0.0.1", dashboard_address=None, silence_logs=40)
            client = Client(cluster)
        else:
            client = _connect(Client, address)
        try:
            client.wait_for_workers(1, timeout=CONNECT_SECONDS)
            workers = len(client.scheduler_info()["workers"]) or 1
            size = chunk_size(first, total - here, workers, executor.chunk_seconds)
            return _stream(client, func, points, here, size, workers, store, done, label, inner, record)
        finally:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()


def configured_scheduler() -> str | None:
    """The scheduler in Dask's own configuration (``scheduler-address``, set by DASK_SCHEDULER_ADDRESS or a
    Dask config file: the user's environment), checked; None when it names none."""
    import dask

    from mechgen.runtime.core.sweep_tasks import SCHEDULER_FORM, scheduler_address

    value = dask.config.get("scheduler-address", None)
    if value is None or value == "":
        return None
    try:
        return scheduler_address(value)
    except ValueError as exc:
        raise InputError(f"Dask's scheduler-address setting {str(value)[:80]!r} is not a scheduler address: {exc}",
                         key="DASK_SCHEDULER_ADDRESS", expected=SCHEDULER_FORM + ", or unset") from None


def _connect(client_class, address: str):
    try:
        return client_class(address, timeout=CONNECT_SECONDS)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:  # refused, timed out, no TLS configuration
        raise InputError(f"no Dask scheduler answers at {address!r}: {type(exc).__name__}: {exc}", key="scheduler",
                         expected="the address of a running scheduler, tcp://host:port, or no scheduler "
                                  "(a LocalCluster is started for the sweep)") from exc


def _stream(client, func, points, start: int, size: int, workers: int, store, done, label, inner: str,
            record: bool) -> tuple[list, int]:
    """Submit chunks of ``size`` points from point ``start`` on, IN_FLIGHT per worker, and collect them as they
    finish."""
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    sweep_id = uuid.uuid4().hex
    bounds = [(lo, min(lo + size, len(points))) for lo in range(start, len(points), size)]
    resubmitted: Counter = Counter()

    def submit(index: int):
        lo, hi = bounds[index]
        tasks = [points[i] for i in range(lo, hi)]
        return client.submit(run_chunk, func, tasks, sweep_id, index, inner, pure=False,
                             key=f"mechgen-sweep-{sweep_id}-{index}-{resubmitted[index]}")

    pending = iter(range(len(bounds)))
    futures = as_completed()
    owner: dict = {}
    for index in itertools.islice(pending, IN_FLIGHT * workers):
        fut = submit(index)
        owner[fut.key] = index
        futures.add(fut)
    for fut in futures:
        index = owner.pop(fut.key)
        lo, hi = bounds[index]
        try:
            _, outcomes = fut.result()
        except BudgetExceeded as exc:
            raise inner_budget(exc, label(lo), inner) from exc
        except KilledWorker:
            if resubmitted[index] >= RESUBMITS:
                raise SweepError(f"sweep points {lo}..{hi - 1} (from {describe(label(lo))}) lost their worker "
                                 f"{RESUBMITS + 1} times over; the cluster keeps failing") from None
            resubmitted[index] += 1
            again = submit(index)
            owner[again.key] = index
            futures.add(again)
            continue
        for offset, outcome in enumerate(outcomes):
            if outcome[0] != OK and not record:
                raise SweepError(f"sweep point {describe(label(lo + offset))} failed: {outcome[0][len('failed: '):]}")
            store(lo + offset, outcome)
        done(hi - lo)
        for nxt in itertools.islice(pending, 1):
            again = submit(nxt)
            owner[again.key] = nxt
            futures.add(again)
    starts = Counter(msg["chunk"] for _, msg in client.get_events(TOPIC) if msg.get("sweep") == sweep_id)
    retried = sorted(i for index, count in starts.items() if count > 1 or resubmitted[index]
                     for i in range(*bounds[index]))
    return retried, len(bounds) + sum(resubmitted.values())

