"""Run one function over a list of parameter points, serially or in local processes.

Order is preserved; a tqdm progress bar goes to stderr when it is a terminal.
An exception at a point is re-raised naming that point.
"""
from __future__ import annotations

import sys

from mechgen.errors import MechgenError
from mechgen.runtime.core.threads import single_thread_worker


class SweepError(MechgenError):
    """A sweep point failed; the message names the point."""


def _bar(total: int, progress: bool, desc: str):
    from tqdm import tqdm  # imported when a sweep runs, not with every scene (startup)

    return tqdm(total=total, desc=desc, disable=not (progress and sys.stderr.isatty()), file=sys.stderr)


def sweep(func, points: list, *, workers: int = 0, progress: bool = True, desc: str = "sweep") -> list:
    """[func(point) for point in points], with ``workers`` > 1 local processes."""
    results: list = [None] * len(points)
    with _bar(len(points), progress, desc) as bar:
        if workers <= 1:
            for i, point in enumerate(points):
                results[i] = _call(func, point)
                bar.update()
            return results
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=workers, initializer=single_thread_worker) as pool:
            futures = [pool.submit(func, point) for point in points]
            for i, fut in enumerate(futures):
                try:
                    results[i] = fut.result()
                except Exception as exc:  # re-raised with the point named
                    raise SweepError(f"sweep point {_describe(points[i])} failed: {exc}") from exc
                bar.update()
    return results


def _call(func, point):
    try:
        return func(point)
    except MechgenError:
        raise
    except Exception as exc:  # re-raised with the point named
        raise SweepError(f"sweep point {_describe(point)} failed: {exc}") from exc


def _describe(point) -> str:
    if isinstance(point, tuple) and point and isinstance(point[-1], dict):
        point = point[-1]
    return repr(point)
