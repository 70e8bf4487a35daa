"""Run one function over a list of parameter points, serially or in local processes.

Order is preserved; a tqdm progress bar with the remaining time goes to stderr when it is a
terminal and the sweep lasts over 2 s (mechgen.runtime.core.budget.Progress). An exception at a
point is re-raised naming that point. A :class:`~mechgen.runtime.core.budget.Budget` bounds the
wall time: after each point the time for all of them is estimated from the points done
(elapsed * total / done) and the sweep is refused as soon as that estimate, trusted after 2 s,
exceeds the budget; an inner analysis's spent budget is re-raised with the point and its key
under ``inner`` (``analysis.max_steps``).
"""
from __future__ import annotations

from mechgen.errors import MechgenError
from mechgen.runtime.core.budget import Budget, BudgetExceeded, Progress
from mechgen.runtime.core.threads import single_thread_worker


class SweepError(MechgenError):
    """A sweep point failed; the message names the point."""


def sweep(func, points: list, *, workers: int = 0, progress: bool = True, desc: str = "sweep",
          budget: Budget | None = None, inner: str = "analysis", labels=None) -> list:
    """[func(point) for point in points], with ``workers`` > 1 local processes, under ``budget``; ``labels[i]``
    names point i in messages (default: the point, or the last dict of a task tuple)."""
    results: list = [None] * len(points)
    total = len(points)

    def label(i: int):
        return labels[i] if labels is not None else points[i]

    def done(i: int) -> None:
        if budget is not None:
            budget.project(i + 1, total, lambda: f"{i + 1:,} of {total:,} points")

    with Progress(total, desc=desc, unit="point", enabled=progress) as bar:
        if workers <= 1:
            for i, point in enumerate(points):
                results[i] = _call(func, point, inner, label(i))
                bar.update()
                done(i)
            return results
        from concurrent.futures import ProcessPoolExecutor

        pool = ProcessPoolExecutor(max_workers=workers, initializer=single_thread_worker)
        try:
            futures = [pool.submit(func, point) for point in points]
            for i, fut in enumerate(futures):
                try:
                    results[i] = fut.result()
                except BudgetExceeded as exc:
                    raise _inner(exc, label(i), inner) from exc
                except MechgenError:
                    raise
                except Exception as exc:  # re-raised with the point named
                    raise SweepError(f"sweep point {_describe(label(i))} failed: {exc}") from exc
                bar.update()
                done(i)
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
    return results


def _inner(exc: BudgetExceeded, point, inner: str) -> BudgetExceeded:
    """An inner analysis's spent budget, with the point and its key under ``inner``."""
    reached = f"{exc.reached} at sweep point {_describe(point)}" if exc.reached else f"sweep point {_describe(point)}"
    return BudgetExceeded(exc.message, key=f"{inner}.{exc.key}" if exc.key else None, reached=reached,
                          analysis=exc.analysis)


def _call(func, point, inner: str, label):
    try:
        return func(point)
    except BudgetExceeded as exc:
        raise _inner(exc, label, inner) from exc
    except MechgenError:
        raise
    except Exception as exc:  # re-raised with the point named
        raise SweepError(f"sweep point {_describe(label)} failed: {exc}") from exc


def _describe(point) -> str:
    if isinstance(point, tuple) and point and isinstance(point[-1], dict):
        point = point[-1]
    return repr(point)
