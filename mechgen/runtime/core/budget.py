"""Work budgets and progress bars of the loops whose length a user controls.

Every such loop (time steps, sweep points, branch points, driving frequencies, Newton iterations)
runs under a :class:`Budget`: at most ``limit`` units of work (``unit``: steps, points ...) and at
most ``seconds`` of wall time. Each has a default that no shipped scene comes near and a scene key
that raises it (``key`` and ``seconds_key``). Reaching either ends the run with
:class:`BudgetExceeded` (exit 1), whose message says what ran out, how far the work got and which
key to raise. Where the work is known before it starts (a fixed-step integration: t_end / dt
steps) :meth:`Budget.refuse` stops it up front; where it can be estimated from the first units (a
sweep's points) :meth:`Budget.project` stops it once the estimate is reliable:

    estimated total = e0 + (elapsed - e0) (total - d0) / (done - d0)        (seconds)

from the rate after the first d0 units (done at e0 s: they carry the one-time costs, a library built or a cache
filled), after at least :data:`PROJECT_AFTER` seconds, refused when it exceeds ``seconds``. An accepted
estimate above :data:`NOTICE_ABOVE` seconds is said once on stderr (the bar below is drawn only on a
terminal), so that a long run through a pipe is not silent.

:class:`Progress` is a tqdm bar on stderr with the remaining time, drawn only when the caller lets
it (the ``progress`` key), stderr is a terminal and the work has lasted :data:`DELAY` seconds, so
quick runs, pipes and tests print nothing.
"""
from __future__ import annotations

import contextlib
import signal
import sys
import threading
import time
from typing import Callable

from mechgen.errors import InputError, MechgenError

#: default wall-time budget of an analysis, seconds (the longest shipped scene's analysis takes ~20 s)
DEFAULT_SECONDS = 600.0
#: the scene key of the wall-time budget, the same in every kind
SECONDS_KEY = "max_seconds"
#: a bar appears after this many seconds (quick runs print nothing)
DELAY = 2.0
#: an estimate from the first units is trusted after this many seconds of them
PROJECT_AFTER = 2.0
#: an accepted estimate longer than this is announced once on stderr, seconds
NOTICE_ABOVE = 30.0


class BudgetExceeded(MechgenError):
    """A work budget ran out (exit 1): names what ran out, how far the work got and the key to raise.

    ``analysis`` is filled in where the analysis is known (``mechgen.analyses.result.run_analysis``),
    ``key`` is relative to the analysis's table (``max_steps``; a sweep's inner one ``analysis.max_steps``).
    """

    def __init__(self, message: str, *, key: str | None = None, reached: str = "", analysis: str = "") -> None:
        self.message, self.key, self.reached, self.analysis = message, key, reached, analysis
        #: the nesting level of the wall_clock backstop that raised it (0: the outermost); None: a loop's own budget
        self.level: int | None = None
        super().__init__(self.paragraph())

    def paragraph(self) -> str:
        """``<analysis>: <message>[; reached <how far>]; raise <key> to allow more``."""
        text = (f"{self.analysis}: " if self.analysis else "") + self.message
        if self.reached:
            text += f"; reached {self.reached}"
        if self.key:
            text += f"; raise '{self.key}' in the analysis's table to allow more"
        return text

    def named(self, analysis: str | None = None, *, prefix: str = "") -> "BudgetExceeded":
        """The same error for the analysis ``analysis`` (kept when already named), its key under ``prefix``."""
        key = f"{prefix}.{self.key}" if prefix and self.key else self.key
        return BudgetExceeded(self.message, key=key, reached=self.reached,
                              analysis=self.analysis or (analysis or ""))

    def __reduce__(self):  # keyword arguments survive a worker process's pickling
        return (_rebuild, (self.message, self.key, self.reached, self.analysis))


def _rebuild(message, key, reached, analysis) -> BudgetExceeded:
    return BudgetExceeded(message, key=key, reached=reached, analysis=analysis)


class Budget:
    """At most ``limit`` units of ``unit`` (None: no count limit) and ``seconds`` of wall time.

    ``what`` names the loop in messages ("RK45 steps"); ``key`` and ``seconds_key`` are the scene
    keys that raise the two limits. The clock starts at construction.
    """

    def __init__(self, what: str, *, limit: int | None = None, key: str | None = None, unit: str = "steps",
                 seconds: float | None = DEFAULT_SECONDS, seconds_key: str = SECONDS_KEY,
                 clock: Callable[[], float] = time.perf_counter) -> None:
        self.what, self.limit, self.key, self.unit = what, limit, key, unit
        self.seconds, self.seconds_key, self.clock = seconds, seconds_key, clock
        self.used = 0
        self.started = clock()
        self.noticed = False
        #: (units, seconds) at the first projection: the baseline of the estimate
        self.first: tuple[int, float] | None = None

    def elapsed(self) -> float:
        """Wall seconds since the budget started."""
        return self.clock() - self.started

    def refuse(self, needed: int, reached: str = "nothing (refused before starting)") -> None:
        """Raise before starting when the work is known to need ``needed`` units, more than the limit."""
        if self.limit is not None and needed > self.limit:
            raise BudgetExceeded(f"{self.what}: needs {needed:,} {self.unit}, more than {self.key} = "
                                 f"{self.limit:,}", key=self.key, reached=reached)

    def spend(self, units: int = 1, reached: Callable[[], str] | str = "") -> None:
        """Count ``units`` more and check both limits; ``reached`` (text, or a function giving it: called only
        on failure) says how far the work got."""
        self.used += units
        if self.limit is not None and self.used > self.limit:
            raise BudgetExceeded(f"{self.what}: stopped after {self.limit:,} {self.unit} ({self.key} = "
                                 f"{self.limit:,})", key=self.key, reached=_text(reached))
        self.check_time(reached)

    def check_time(self, reached: Callable[[], str] | str = "", elapsed: float | None = None) -> None:
        """Raise when the wall time is spent (``elapsed``: the caller's reading of the clock, so that one decision
        reads one time)."""
        elapsed = self.elapsed() if elapsed is None else elapsed
        if self.seconds is not None and elapsed > self.seconds:
            raise BudgetExceeded(f"{self.what}: stopped after {elapsed:.1f} s of wall time "
                                 f"({self.seconds_key} = {self.seconds:g})", key=self.seconds_key,
                                 reached=_text(reached))

    def project(self, done: int, total: int, reached: Callable[[], str] | str = "") -> None:
        """After ``done`` of ``total`` units: refuse when the estimate exceeds the wall-time budget. The first call
        sets the baseline (d0 units at e0 s: the first units carry one-time costs, a library built or a cache
        filled, that the others do not repeat); later ones estimate e0 + (elapsed - e0) (total - d0) / (done - d0),
        trusted after PROJECT_AFTER seconds. The budget itself is checked always."""
        elapsed = self.elapsed()
        if self.first is None and done > 0:
            self.first = (done, elapsed)
        d0, e0 = self.first if self.first is not None else (0, 0.0)
        if self.seconds is not None and done > d0 and elapsed >= min(PROJECT_AFTER, self.seconds) and done < total:
            estimate = e0 + (elapsed - e0) * (total - d0) / (done - d0)
            if estimate > self.seconds:
                raise BudgetExceeded(f"{self.what}: {total:,} {self.unit} would take about {_duration(estimate)} "
                                     f"at the rate of {done - d0:,} after the first {d0:,} ({elapsed:.1f} s in "
                                     f"all), more than {self.seconds_key} = {self.seconds:g}", key=self.seconds_key,
                                     reached=_text(reached))
            if estimate > NOTICE_ABOVE and not self.noticed:
                self.noticed = True
                sys.stderr.write(f"mechgen: {self.what}: {total:,} {self.unit} will take about "
                                 f"{_duration(estimate)} ({self.seconds_key} = {self.seconds:g})\n")
        self.check_time(reached, elapsed)  # the same reading: past the budget, the estimate (>= it) said so first


def require_seconds(estimate: float, seconds: float | None, what: str, *, key: str, basis: str,
                    expected: str | None = None) -> None:
    """Refuse up front (InputError, exit 2 at ``key``, the scene key that sets the size of the work) work whose
    wall time, estimated before it starts as ``estimate`` seconds (``basis``: the measured unit cost times the
    units, as the caller states it), exceeds the analysis's budget ``seconds`` (max_seconds; None: no budget).

    Estimates are made from per-unit costs measured on a 2-core machine (the constants beside each caller) and
    count the least work the run can do, so that a run refused here would have been stopped by the budget anyway;
    nothing has started when this raises."""
    if seconds is None or not estimate > seconds:
        return
    hint = expected or f"a smaller {key.rpartition('.')[2]}"
    raise InputError(f"{what} would take about {_duration(estimate)} ({basis}), more than the wall-time budget "
                     f"{SECONDS_KEY} = {seconds:g}; nothing was started", key=key,
                     expected=f"{hint}, or {SECONDS_KEY} raised above {estimate:.3g} in the analysis's table")


def _text(reached: Callable[[], str] | str) -> str:
    return reached() if callable(reached) else reached


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.3g} days"


class Progress:
    """A progress bar with the remaining time (tqdm on stderr) up to ``total`` (a count or a time).

    Drawn only when ``enabled``, stderr is a terminal and the work has lasted DELAY seconds; tqdm is
    imported only then. Use as a context manager; :meth:`to` moves the bar to an absolute position.
    """

    def __init__(self, total: float, *, desc: str, unit: str = "it", enabled: bool = True,
                 delay: float = DELAY) -> None:
        self.bar = None
        self.position = 0.0
        if enabled and _is_terminal(sys.stderr):
            from tqdm import tqdm  # only when a bar can be drawn (startup)

            self.bar = tqdm(total=total, desc=desc, unit=unit, delay=delay, file=sys.stderr, leave=False,
                            dynamic_ncols=True)

    @property
    def shown(self) -> bool:
        """Whether a bar may be drawn at all (a terminal, and enabled)."""
        return self.bar is not None

    def update(self, amount: float = 1) -> None:
        """Move the bar on by ``amount``."""
        if self.bar is not None:
            self.bar.update(amount)

    def to(self, position: float) -> None:
        """Move the bar to ``position``."""
        if self.bar is not None and position > self.position:
            self.bar.update(position - self.position)
            self.position = position

    def close(self) -> None:
        """Remove the bar."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


#: the backstop fires this long after an analysis's own wall-time budget (its loops' checks come first):
#: max_seconds x BACKSTOP_GRACE + BACKSTOP_MARGIN s, so that a loop's own check, with its informative message
#: (the steps done, where it stopped), runs first even for a tiny budget
BACKSTOP_GRACE = 1.10
BACKSTOP_MARGIN = 2.0


#: the levels of the wall_clock timers set now, outermost first (one process's main thread)
_CLOCKS: list[int] = []


def clock_depth() -> int:
    """How many wall_clock timers are set now: a BudgetExceeded whose ``level`` is below the depth read before a
    call came from a timer set outside that call (a sweep's own budget, not its point's)."""
    return len(_CLOCKS)


@contextlib.contextmanager
def wall_clock(seconds: float | None, what: str):
    """The wall-time budget of a whole analysis, for every kind (issue 33): a real-time timer (SIGALRM) that
    raises BudgetExceeded (key ``max_seconds``) in the main thread once ``seconds`` x BACKSTOP_GRACE +
BACKSTOP_MARGIN have passed,
    a backstop behind the loops' own budgets for the work that has none (an eigen-solve, a rod's Newton steps).
    Python code is interrupted between bytecodes; a long call into compiled code ends first. Off outside the
    main thread, where no timer can be set, and for ``seconds`` None; under a caller's timer that fires first it
    sets none, and a later one is restored with what is left of it."""
    if seconds is None or threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        yield
        return
    limit = seconds * BACKSTOP_GRACE + BACKSTOP_MARGIN
    pending = signal.getitimer(signal.ITIMER_REAL)[0]
    if 0 < pending <= limit:  # a caller's own timer (a test harness, an outer analysis) fires first: leave it
        yield
        return

    level = len(_CLOCKS)

    def expired(signum, frame):
        exc = BudgetExceeded(f"{what}: stopped after {limit:.1f} s of wall time ({SECONDS_KEY} = {seconds:g})",
                             key=SECONDS_KEY)
        exc.level = level
        raise exc

    started = time.monotonic()
    previous_handler = signal.signal(signal.SIGALRM, expired)
    previous_left, _ = signal.setitimer(signal.ITIMER_REAL, limit)
    _CLOCKS.append(level)
    try:
        yield
    finally:
        _CLOCKS.pop()
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous_handler)
        if previous_left > 0:  # an outer timer: what is left of it
            signal.setitimer(signal.ITIMER_REAL, max(previous_left - (time.monotonic() - started), 1e-3))
