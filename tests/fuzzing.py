"""Scene fuzzing harness: mutate the shipped scenes, run each through ``mechgen.cli.main`` and judge the outcome.

The contract checked (issue 12 section 5, docs/guide.md "exit codes"): a run of ``mechgen run SCENE`` either

* exits 0 (and wrote its ``--json`` file), or
* exits 2 with one ``mechgen: ...`` paragraph on stderr that names the scene file and a key
  (a key of the scene the user wrote, or the flag), or
* exits 1 with ``mechgen: SomeError: message`` (a named computation failure),

and never ends in a Python traceback, a crash, a hang beyond the case's wall-clock limit, or a
half-written output (no ``--json`` file and no ``.tmp-*`` file after a failed run).

A case is run in a forked child of the calling process (``ISOLATE``): the child inherits the imported
modules (no interpreter start, no re-import), calls ``main`` in-process with stdout/stderr captured,
under an address-space limit (``MEMORY_HEADROOM`` above what the parent uses) and a SIGALRM at the
case's limit that raises :class:`CaseTimeout` where the run is (so the finding says where it hung);
the parent kills the child ``KILL_GRACE`` seconds later if it is stuck in compiled code. Where
``os.fork`` does not exist the case runs in this process under SIGALRM alone. Everything a case
writes goes into its work folder (the scene copy, ``--json``, the child's current directory).

Mutations (:func:`mutate`): dropped keys and array items, wrong types (str <-> number <-> list <-> table),
huge / negative / zero / subnormal / NaN / infinite numbers and integers past 64 bits, unknown keys
(also keys of other tables, misplaced), emptied tables and arrays, unicode and hostile strings, arrays
and tables nested hundreds deep, and ``--set`` overrides. The ``model`` key only ever gets values from
:data:`MODEL_POOL` (a model reference can name importable code: ``package.module:attribute``).

Exploratory run (several thousand cases, findings deduplicated by exception type and raising location)::

    PYTHONPATH=$PWD python tests/fuzzing.py --examples 3000 --seed 1 --out /tmp/fuzz-findings.json
"""
from __future__ import annotations

import contextlib
import copy
import io
import json
import math
import os
import re
import select
import signal
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ImportError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"

ISOLATE = hasattr(os, "fork")
MEMORY_HEADROOM = 3 << 30  # bytes of address space a case may add to what the parent holds
KILL_GRACE = 5.0  # seconds after the SIGALRM before a stuck child is killed
# A case whose alarm finds it deriving or compiling (mechgen.symbolic, mechgen.codegen: bounded by the model,
# slow for the first build of a new specialisation on a loaded machine) gets this many more limits.
COMPILE_EXTENSIONS = 3
COMPILING = (f"{os.sep}mechgen{os.sep}symbolic{os.sep}", f"{os.sep}mechgen{os.sep}codegen{os.sep}")

# Per-scene reductions applied before mutating: the same scene, cheaper (fewer sweep points, shorter
# simulations, coarser meshes), so that a few hundred cases fit in a CI minute. Paths as in ``get_path``.
CHEAP = {
    "fpu_chain": {("params", "N"): 8, ("analysis", 1, "t_end"): 20.0},
    "fpu_recurrence": {("analysis", 0, "t_end"): 200.0},
    "fpu_large": {("params", "N"): 1000, ("analysis", 0, "t_end"): 10.0},
    "spring_pendulum": {("analysis", 2, "t_end"): 2.0},
    "laval_rotor": {("analysis", 1, "over", "Omega", "num"): 4},
    "jeffcott_unbalance": {("analysis", 0, "over", "Omega", "num"): 20},
    "beam_modes": {("params", "N"): 4},
    "timoshenko_modes": {("params", "N"): 4},
    "beck_column": {("params", "N"): 8, ("analysis", 1, "over", "P", "num"): 4},
    "moving_string": {("params", "N"): 8, ("analysis", 1, "over", "c", "num"): 4},
    "rotating_string": {("params", "N"): 8, ("analysis", 1, "over", "Omega", "num"): 4},
    "ross_example_rotor": {("analysis", 1, "over", "Omega"): [0.0, 500.0],
                           ("analysis", 2, "over", "Omega", "num"): 3},
    "stepped_rotor": {("analysis", 1, "over", "Omega"): [0.0, 1000.0],
                      ("analysis", 2, "over", "Omega", "num"): 3},
    "balloon_stability": {("analysis", 1, "max_points"): 3},
    "balloon_frequencies": {("analysis", 1, "max_points"): 3, ("analysis", 3, "max_points"): 3,
                            ("analysis", 4, "max_points"): 3},
    "balloon_branches": {("analysis", 1, "max_points"): 3, ("analysis", 5, "max_points"): 3},
}
# Scenes whose cheap form runs in well under a second once compiled: the CI fuzz draws from these.
FAST_SCENES = ("laval_rotor", "timoshenko_modes", "rotating_string", "moving_string", "beam_modes",
               "fpu_chain", "spring_pendulum")
ALL_SCENES = tuple(sorted(CHEAP))

MODEL_POOL = ("laval_rotor", "fpu_chain", "spring_pendulum", "euler_bernoulli_beam", "timoshenko_beam",
              "rotating_string", "moving_string", "follower_column", "", "warp_drive", "Laval_Rotor",
              "laval_rotor ", "missing_model.py", "./nowhere/model.py", "\u00e9\u00e8", "a" * 300)
SPECIAL_NUMBERS = (0, -0.0, 0.0, -1, -5, 1, 2, 3, 0.5, 1e-300, 5e-324, -1e-300, 1e200, -1e200, 1e308,
                   math.inf, -math.inf, math.nan, 2**31, 2**63, 2**64 + 1, 10**310, -(10**310), 999999,
                   1e6, 1e9, 1e15, 1e-15, 17.5, 0.1, -0.5)
HOSTILE_STRINGS = ("", " ", "abc", "1.0", "1e309", "nan", "inf", "-inf", "0x10", "2*pi*(", "2*pi*100",
                   "N", "m", "__import__('os').system('echo pwned')", 'x); import os; os.system("echo pwned") #',
                   "*/ int x; /*", '"""', "'", "\\", "\n", "\x00", "\x7f", "\u202e\u0645\u0631\u062d\u0628\u0627",
                   "\U0001f680" * 3, "\u00e9t\u00e9", "e" * 20000, "${HOME}", "$(id)", "`id`", "%s%n",
                   "../../etc/passwd", "CON", "disk", "bearing", "pinned-pinned", "hermite", "stability",
                   "leapfrog", "c", "numpy", "casadi", "true", "[1, 2]", "{}", "1/0", "sqrt(-1)", "Omega**1000")
# Keys a user might add by mistake: typos, keys of other tables and analyses, odd names. Never
# ``workers`` (a sweep would fork that many processes).
EXTRA_KEYS = ("colour", "Nn", "n", "t_end", "dt", "count", "method", "about", "kind", "name", "over",
              "params", "analysis", "backend", "model", "title", "free", "coordinates", "tol", "samples",
              "quadrature", "num", "start", "stop", "q0", "guess", "initial_mode", "amplitude", "series",
              "outputs", "aliases", "iterations", "residual_norm", "coordinates", "t_end", "__class__",
              "\u00fc", "a.b", "", " ", "x" * 200, "N", "L", "m", "rtol", "atol", "hold", "at", "parts",
              "segments", "shape", "bounds", "direction", "max_points", "step", "mesh", "progress")
DEEP = 500  # nesting depth of the deep arrays and tables


class CaseTimeout(BaseException):
    """Raised by SIGALRM in a case past its wall-clock limit (BaseException: no ``except Exception`` eats it)."""


@dataclass(frozen=True)
class Deep:
    """A value nested ``depth`` times: ``[[[...1...]]]`` (array) or ``{ a = { a = ... 1 } }`` (table).

    Written as text without recursion, so that the harness itself never hits the recursion limit.
    """

    kind: str
    depth: int = DEEP


@dataclass
class Case:
    """One scene run: the scene document (already mutated), extra CLI arguments, what was done to it."""

    scene: str
    doc: dict
    mutations: list = field(default_factory=list)
    args: list = field(default_factory=list)
    limit_s: float = 20.0

    def describe(self) -> str:
        """One line per mutation (op, dotted key, value shown briefly)."""
        return "; ".join(f"{op} {dotted(path)}{'' if value is _NOTHING else ' = ' + brief(value)}"
                         for op, path, value in self.mutations) + (f" args {self.args}" if self.args else "")


_NOTHING = object()


@dataclass
class Outcome:
    """What one run did: exit code (None: it did not return), captured output, the exception if any."""

    code: int | None
    out: str
    err: str
    seconds: float
    exc_type: str | None = None
    exc_message: str = ""
    last_frame: str = ""
    mechgen_frame: str = ""
    tb: str = ""
    status: str = "returned"  # returned | raised | timeout | killed | crashed
    extended: int = 0  # limits added because the alarm found the case deriving or compiling
    leftovers: list = field(default_factory=list)


# --- the scene document -----------------------------------------------------------------------------------------

def base_doc(name: str, cheap: bool = True) -> dict:
    """The shipped scene ``scenes/NAME.toml`` parsed, with its :data:`CHEAP` reductions when ``cheap``."""
    doc = tomllib.loads((SCENES / f"{name}.toml").read_text(encoding="utf-8"))
    if cheap:
        for path, value in CHEAP.get(name, {}).items():
            set_path(doc, path, copy.deepcopy(value))
    return doc


def get_path(doc, path):
    """The node at ``path`` (keys and 0-based array indices)."""
    node = doc
    for part in path:
        node = node[part]
    return node


def set_path(doc, path, value) -> None:
    """Replace (or add) the node at ``path``."""
    get_path(doc, path[:-1])[path[-1]] = value


def del_path(doc, path) -> None:
    """Remove the node at ``path`` from its table or array."""
    del get_path(doc, path[:-1])[path[-1]]


def walk(doc, path=()):
    """Every (path, node) below ``doc``, parents before children (the root itself excluded)."""
    items = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) else ()
    for key, value in items:
        yield path + (key,), value
        yield from walk(value, path + (key,))


def dotted(path) -> str:
    """``("analysis", 1, "t_end")`` -> ``analysis[2].t_end`` (the 1-based form mechgen's messages use)."""
    text = ""
    for part in path:
        text += f"[{part + 1}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "<root>"


def brief(value, width: int = 60) -> str:
    """A short repr of a mutation value."""
    if isinstance(value, Deep):
        return f"<{value.kind} nested {value.depth} deep>"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**20:
        return f"<int of {len(str(abs(value)))} digits{' (negative)' if value < 0 else ''}>"
    text = repr(value)
    return text if len(text) <= width else text[:width] + f"...<{len(text)} chars>"


def keys_of(doc) -> set[str]:
    """Every table key in the document (what a message may name)."""
    return {part for path, _ in walk(doc) for part in path[-1:] if isinstance(part, str)}


# --- a minimal TOML writer --------------------------------------------------------------------------------------

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def toml_key(key: str) -> str:
    """A key, bare when TOML allows it, else a basic string."""
    return key if _BARE.match(key) else toml_string(key)


def toml_string(text: str) -> str:
    """A TOML basic string: quote, backslash and control characters escaped."""
    out = ['"']
    for ch in text:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def toml_value(value) -> str:
    """An inline TOML value (tables inline, arrays possibly mixed, as TOML 1.0 allows)."""
    if isinstance(value, Deep):
        if value.kind == "array":
            return "[" * value.depth + "1" + "]" * value.depth
        return "{ a = " * value.depth + "1" + " }" * value.depth
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + " }" if value else "{}"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def dumps(doc: dict) -> str:
    """The document as TOML: root scalars first, then ``[table]`` and ``[[array of tables]]`` sections."""
    head, tail = [], []
    for key, value in doc.items():
        if isinstance(value, dict):
            tail.append(f"\n[{toml_key(key)}]")
            tail.extend(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items())
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                tail.append(f"\n[[{toml_key(key)}]]")
                tail.extend(f"{toml_key(k)} = {toml_value(v)}" for k, v in item.items())
        else:
            head.append(f"{toml_key(key)} = {toml_value(value)}")
    return "\n".join(head + tail) + "\n"


# --- mutations (hypothesis) -------------------------------------------------------------------------------------

def _strategies():
    from hypothesis import strategies as st

    numbers = st.one_of(st.sampled_from(SPECIAL_NUMBERS), st.integers(-(2**70), 2**70),
                        st.floats(allow_nan=True, allow_infinity=True))
    strings = st.one_of(st.sampled_from(HOSTILE_STRINGS), st.text(max_size=30))
    scalars = st.one_of(numbers, strings, st.booleans())
    lists = st.one_of(st.sampled_from(([], [1], ["disk"], [1, "a"], [[]], [{}], [math.nan], [0.0, 1.0, 2.0])),
                      st.lists(scalars, max_size=4))
    tables = st.one_of(st.sampled_from(({}, {"x": 1}, {"start": 0.0, "stop": 1.0, "num": 3},
                                        {"kind": "modes"}, {"start": 0.0, "stop": 1.0, "num": 10**9})),
                       st.dictionaries(st.sampled_from(EXTRA_KEYS), scalars, max_size=3))
    deep = st.builds(Deep, st.sampled_from(("array", "table")), st.sampled_from((50, DEEP)))
    anything = st.one_of(scalars, lists, tables, deep)
    return st, numbers, strings, lists, tables, deep, anything


def other_type(draw, value):
    """A value of another TOML type than ``value`` (str <-> number <-> bool <-> list <-> table)."""
    st, numbers, strings, lists, tables, deep, _ = _strategies()
    if isinstance(value, bool):
        pool = [numbers, strings, lists, tables]
    elif isinstance(value, (int, float)):
        pool = [strings, st.booleans(), lists, tables]
    elif isinstance(value, str):
        pool = [numbers, st.booleans(), lists, tables]
    elif isinstance(value, list):
        pool = [numbers, strings, tables]
    else:
        pool = [numbers, strings, lists]
    return draw(st.one_of(*pool, deep))


OPS = ("drop", "retype", "number", "string", "unknown_key", "empty", "deep", "set")


def mutate(draw, case: Case) -> None:
    """Apply one drawn mutation to ``case`` (its document or its arguments), recording it."""
    st, numbers, strings, lists, tables, deep, anything = _strategies()
    doc = case.doc
    nodes = list(walk(doc))
    op = draw(st.sampled_from(OPS))
    pick = lambda cands: cands[draw(st.integers(0, len(cands) - 1))] if cands else None  # noqa: E731
    is_model = lambda path: path[-1:] == ("model",)  # noqa: E731

    if op == "drop":
        target = pick([p for p, _ in nodes])
        if target is not None:
            del_path(doc, target)
            case.mutations.append(("drop", target, _NOTHING))
            return
    elif op == "retype":
        target = pick([(p, v) for p, v in nodes if not is_model(p)])
        if target is not None:
            value = other_type(draw, target[1])
            set_path(doc, target[0], value)
            case.mutations.append(("retype", target[0], value))
            return
    elif op == "number":
        cands = [(p, v) for p, v in nodes if isinstance(v, (int, float)) and not isinstance(v, bool)]
        target = pick(cands or [(p, v) for p, v in nodes if not isinstance(v, (dict, list)) and not is_model(p)])
        if target is not None:
            value = draw(numbers)
            set_path(doc, target[0], value)
            case.mutations.append(("number", target[0], value))
            return
    elif op == "string":
        target = pick([(p, v) for p, v in nodes if isinstance(v, str)])
        if target is not None:
            value = draw(st.sampled_from(MODEL_POOL)) if is_model(target[0]) else draw(strings)
            set_path(doc, target[0], value)
            case.mutations.append(("string", target[0], value))
            return
    elif op == "empty":
        target = pick([(p, v) for p, v in nodes if isinstance(v, (dict, list))] + [((k,), doc[k]) for k in doc
                                                                                   if isinstance(doc[k], (dict, list))])
        if target is not None:
            value = {} if isinstance(target[1], dict) else []
            set_path(doc, target[0], value)
            case.mutations.append(("empty", target[0], value))
            return
    elif op == "deep":
        target = pick([p for p, v in nodes if not is_model(p)])
        if target is not None:
            value = draw(deep)
            set_path(doc, target, value)
            case.mutations.append(("deep", target, value))
            return
    elif op == "set":
        params = doc.get("params") if isinstance(doc.get("params"), dict) else {}
        name = draw(st.one_of(st.sampled_from(sorted(params) or ["m"]), st.sampled_from(EXTRA_KEYS)))
        text = draw(st.one_of(st.sampled_from(("0", "-0", "-5", "1e308", "1e309", "nan", "inf", "1" * 310,
                                               "2*pi", "2*pi*(", "", "=", "a=b", "disk", "1e-300", "5e-324")),
                              st.builds(str, numbers)))
        case.args += ["--set", f"{name}={text}"]
        case.mutations.append(("set", ("--set",), f"{name}={text}"))
        return
    # unknown_key (and the fallback of an op that found nothing to act on)
    tables_ = [((), doc)] + [(p, v) for p, v in nodes if isinstance(v, dict)]
    where = pick(tables_)
    key = draw(st.sampled_from(EXTRA_KEYS))
    value = draw(anything)
    if is_model((key,)):
        value = draw(st.sampled_from(MODEL_POOL))
    set_path(doc, where[0] + (key,), value)
    case.mutations.append(("unknown_key", where[0] + (key,), value))


def case_strategy(scenes=FAST_SCENES, max_mutations: int = 3, limit_s: float = 20.0):
    """Hypothesis strategy of :class:`Case`: a (cheapened) shipped scene with 1..max_mutations mutations."""
    from hypothesis import strategies as st

    @st.composite
    def cases(draw):
        name = draw(st.sampled_from(tuple(scenes)))
        case = Case(name, base_doc(name), limit_s=limit_s)
        for _ in range(draw(st.integers(1, max_mutations))):
            mutate(draw, case)
        return case

    return cases()


# --- running a case ---------------------------------------------------------------------------------------------

def _vm_bytes() -> int | None:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def _limit_memory(headroom: int) -> None:
    try:
        import resource
    except ImportError:  # pragma: no cover - not POSIX
        return
    now = _vm_bytes()
    if now is None:
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = now + headroom
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))


def _frame(fs) -> str:
    return f"{fs.filename}:{fs.lineno} in {fs.name}"


def _short(filename: str) -> str:
    text = filename.replace(str(ROOT) + os.sep, "")
    cut = text.find("site-packages" + os.sep)
    return text[cut + len("site-packages") + 1:] if cut >= 0 else text


def _call_main(argv, limit_s: float) -> dict:
    """Run ``main(argv)`` here with output captured and SIGALRM at ``limit_s``; a JSON-able record."""
    from mechgen.cli import main

    out, err = io.StringIO(), io.StringIO()
    record = {"code": None, "status": "returned", "exc_type": None, "exc_message": "", "last_frame": "",
              "mechgen_frame": "", "tb": ""}

    extended = [0]

    def on_alarm(signum, frame):
        here = frame
        while here is not None and not any(part in here.f_code.co_filename for part in COMPILING):
            here = here.f_back
        if here is not None and extended[0] < COMPILE_EXTENSIONS:
            extended[0] += 1
            signal.setitimer(signal.ITIMER_REAL, limit_s)
            return
        raise CaseTimeout(f"past {limit_s * (1 + extended[0])} s" + (" (deriving or compiling)" if here else ""))

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, limit_s)
    start = time.perf_counter()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            record["code"] = main(list(argv))
    except BaseException as exc:  # noqa: BLE001 - every escape is a finding
        signal.setitimer(signal.ITIMER_REAL, 0)
        frames = traceback.extract_tb(exc.__traceback__)
        record["status"] = "timeout" if isinstance(exc, CaseTimeout) else "raised"
        record["exc_type"] = type(exc).__name__
        record["exc_message"] = str(exc)[:500]
        if frames:
            record["last_frame"] = _short(_frame(frames[-1]))
            ours = [f for f in frames if f"{os.sep}mechgen{os.sep}" in f.filename
                    and not f.filename.endswith(f"{os.sep}mechgen{os.sep}cli.py")]
            record["mechgen_frame"] = _short(_frame(ours[-1])) if ours else record["last_frame"]
        record["tb"] = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))[-6000:]
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    record["seconds"] = time.perf_counter() - start
    record["extended"] = extended[0]
    record["out"] = out.getvalue()[-4000:]
    record["err"] = err.getvalue()[-4000:]
    return record


def run_argv(argv, workdir: Path, limit_s: float, isolate: bool = ISOLATE) -> Outcome:
    """``main(argv)`` with the current directory in ``workdir``: in a forked child (``isolate``) or here."""
    if not isolate:
        cwd = os.getcwd()
        os.chdir(workdir)
        try:
            rec = _call_main(argv, limit_s)
        finally:
            os.chdir(cwd)
        return Outcome(**{k: rec[k] for k in Outcome.__dataclass_fields__ if k in rec})
    sys.stdout.flush()
    sys.stderr.flush()
    rfd, wfd = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: run, send the record, never return into the caller's code
        status = 0
        try:
            os.close(rfd)
            os.chdir(workdir)
            _limit_memory(MEMORY_HEADROOM)
            data = json.dumps(_call_main(argv, limit_s)).encode()
            with os.fdopen(wfd, "wb") as fh:
                fh.write(data)
        except BaseException:  # noqa: BLE001
            status = 3
        finally:
            os._exit(status)
    os.close(wfd)
    chunks, start = [], time.perf_counter()
    deadline = time.monotonic() + limit_s * (1 + COMPILE_EXTENSIONS) + KILL_GRACE
    killed = False
    with os.fdopen(rfd, "rb") as fh:
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                os.kill(pid, signal.SIGKILL)
                killed = True
                break
            ready, _, _ = select.select([fh], [], [], min(left, 1.0))
            if ready:
                chunk = os.read(fh.fileno(), 1 << 16)
                if not chunk:
                    break
                chunks.append(chunk)
    _, wstatus = os.waitpid(pid, 0)
    seconds = time.perf_counter() - start
    if killed:
        return Outcome(None, "", "", seconds, status="killed", exc_type="Hang",
                       exc_message=f"no return {KILL_GRACE} s after the last alarm (stuck in compiled code)")
    try:
        rec = json.loads(b"".join(chunks).decode())
    except ValueError:
        sig = os.WTERMSIG(wstatus) if os.WIFSIGNALED(wstatus) else None
        return Outcome(None, "", "", seconds, status="crashed", exc_type="Crash",
                       exc_message=f"child died (signal {sig}, status {wstatus})")
    return Outcome(**{k: rec[k] for k in Outcome.__dataclass_fields__ if k in rec})


def run_case(case: Case, workdir: Path, isolate: bool = ISOLATE) -> Outcome:
    """Write the case's scene as ``workdir/SCENE.toml`` and run it with ``--json`` into ``workdir``
    (unless the case's own arguments name a ``--json`` target); after a failed run, list what it left
    behind (the JSON target, ``.tmp-*`` files anywhere under ``workdir``)."""
    workdir.mkdir(parents=True, exist_ok=True)
    scene = workdir / f"{case.scene}.toml"
    scene.write_text(dumps(case.doc), encoding="utf-8")
    target = workdir / "out.json"
    own = [] if "--json" in case.args else ["--json", str(target)]
    outcome = run_argv(["run", str(scene)] + own + list(case.args), workdir, case.limit_s, isolate)
    if outcome.code != 0:
        outcome.leftovers = sorted(str(p.relative_to(workdir)) for p in workdir.rglob("*")
                                   if p.name.startswith(".tmp-") or (p == target and not partial_json(p)))
    return outcome


def partial_json(path: Path) -> bool:
    """A failed run may leave its --json only whole and saying so: the analyses before the failure, then the
    failed one as an entry with its ``error`` (issue 25: results survive a failure)."""
    try:
        analyses = json.loads(path.read_text())["analyses"]
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return bool(analyses) and "error" in analyses[-1] and all("error" not in a for a in analyses[:-1])


# --- judging ----------------------------------------------------------------------------------------------------

_QUOTED = re.compile(r"'([^']*)'|\"([^\"]*)\"|`([^`]*)`")
_NAMED_FAILURE = re.compile(r"^mechgen: ([A-Z]\w*): \S")
FLAGS = ("--set", "--json", "--plot", "--backend")


def last_message(err: str) -> str:
    """The ``mechgen: ...`` paragraph the CLI printed (the last such line)."""
    lines = [line for line in err.splitlines() if line.startswith("mechgen:")]
    return lines[-1] if lines else ""


def names_a_key(message: str, keys) -> bool:
    """The message quotes a key (``'params.N'``, ``'analysis[2].t_end'``, ``'N'``) from ``keys`` or a flag."""
    keys = set(keys) | set(FLAGS)
    for match in _QUOTED.finditer(message):
        text = next(g for g in match.groups() if g is not None).strip("'\"`")
        parts = re.split(r"[.\[\]=\s\"']+", text)
        if text in keys or any(part in keys for part in parts if part):
            return True
        if text.endswith("...") and len(text) > 23 and any(key.startswith(text[:-3]) for key in keys):
            return True  # a long key shortened by the message
    return any(flag in message for flag in FLAGS)


def judge(outcome: Outcome, scene_file: str, keys, accept=(0, 1, 2), key_required: bool = True) -> list[str]:
    """The ways ``outcome`` breaks the contract (empty: it kept it). ``accept``: the exit codes allowed."""
    problems = []
    if outcome.status != "returned":
        where = outcome.mechgen_frame or outcome.last_frame
        problems.append(f"{outcome.status}: {outcome.exc_type}: {outcome.exc_message[:200]}"
                        + (f" (at {where})" if where else ""))
        return problems
    code, message = outcome.code, last_message(outcome.err)
    if "Traceback (most recent call last)" in outcome.err:
        problems.append("a traceback on stderr")
    if code not in accept:
        problems.append(f"exit {code}, expected one of {tuple(accept)}: {message[:300]}")
    if code == 2:
        on_the_command_line = any(f"at key '{flag}" in message for flag in FLAGS)
        if scene_file not in message and not on_the_command_line:
            problems.append(f"exit 2 without the file {scene_file!r}: {message[:300]}")
        if key_required and not names_a_key(message, keys):
            problems.append(f"exit 2 without a key: {message[:300]}")
    elif code == 1:
        m = _NAMED_FAILURE.match(message)
        if not m:
            problems.append(f"exit 1 without a named failure: {message[:300] or outcome.err[-300:]}")
        elif m.group(1) == "BuildError":
            problems.append(f"exit 1 with BuildError (a mechgen bug by its own definition): {message[:300]}")
    if code != 0 and outcome.leftovers:
        problems.append(f"half-written output after exit {code}: {outcome.leftovers}")
    return problems


def check_case(case: Case, workdir: Path, isolate: bool = ISOLATE) -> tuple[Outcome, list[str]]:
    """Run a case and judge it against the contract (keys: the mutated and the original scene's)."""
    outcome = run_case(case, workdir, isolate)
    keys = keys_of(case.doc) | keys_of(base_doc(case.scene)) | {
        p for _, path, _ in case.mutations for p in path if isinstance(p, str)}
    return outcome, judge(outcome, f"{case.scene}.toml", keys)


def warm_up(scenes, workdir: Path) -> dict[str, Outcome]:
    """Run each unmutated (cheap) scene once in this process: compiles and imports land in the parent."""
    done = {}
    for name in scenes:
        done[name] = run_case(Case(name, base_doc(name), limit_s=300.0), workdir / f"warm-{name}", isolate=False)
    return done


# --- exploratory run --------------------------------------------------------------------------------------------

def finding_key(outcome: Outcome, problems: list[str]) -> tuple:
    """Deduplication key: (exception type, raising location in mechgen) or the kind of contract break."""
    if outcome.status == "timeout":  # where a loop was interrupted varies by line: the file says enough
        return (outcome.status, outcome.exc_type, (outcome.mechgen_frame or outcome.last_frame).split(":")[0])
    if outcome.status != "returned":
        return (outcome.status, outcome.exc_type, outcome.mechgen_frame or outcome.last_frame)
    first = problems[0]
    kind = first.split(":")[0]
    if outcome.code == 1:
        m = _NAMED_FAILURE.match(last_message(outcome.err))
        return ("exit 1", kind, m.group(1) if m else "")
    return (f"exit {outcome.code}", kind, "")


def explore(examples: int, seed: int, out: Path, scenes=ALL_SCENES, limit_s: float = 20.0) -> dict:
    """Run ``examples`` fuzz cases; write deduplicated findings (with counts and one example each) to ``out``."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import seed as hseed

    base = Path(tempfile.mkdtemp(prefix="mechgen-fuzz-"))
    from hypothesis.configuration import set_hypothesis_home_dir

    set_hypothesis_home_dir(base / "hypothesis")
    warm = warm_up(scenes, base)
    for name, o in warm.items():
        print(f"warm {name}: exit {o.code} {o.status} {o.seconds:.1f} s", flush=True)
    findings: dict = {}
    stats = {"cases": 0, "exit": {}, "seconds": 0.0}

    @hseed(seed)
    @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(case_strategy(scenes, limit_s=limit_s))
    def one(case):
        n = stats["cases"]
        stats["cases"] += 1
        workdir = Path(tempfile.mkdtemp(dir=base, prefix=f"c{n:05d}-"))
        outcome, problems = check_case(case, workdir)
        stats["seconds"] += outcome.seconds
        label = str(outcome.code) if outcome.status == "returned" else outcome.status
        stats["exit"][label] = stats["exit"].get(label, 0) + 1
        if problems:
            key = " | ".join(map(str, finding_key(outcome, problems)))
            entry = findings.setdefault(key, {"count": 0, "example": None, "scenes": {}})
            entry["count"] += 1
            entry["scenes"][case.scene] = entry["scenes"].get(case.scene, 0) + 1
            if entry["example"] is None or len(case.describe()) < len(entry["example"]["mutations"]):
                entry["example"] = {"scene": case.scene, "mutations": case.describe(), "problems": problems,
                                    "exception": f"{outcome.exc_type}: {outcome.exc_message[:300]}",
                                    "last_frame": outcome.last_frame, "mechgen_frame": outcome.mechgen_frame,
                                    "stderr": last_message(outcome.err)[:500], "seconds": round(outcome.seconds, 2),
                                    "tb_tail": outcome.tb[-1500:]}
        if n % 50 == 0:
            print(f"{n} cases, {len(findings)} findings, {stats}", flush=True)
            out.write_text(json.dumps({"stats": stats, "findings": findings}, indent=1, default=str))
        import shutil

        shutil.rmtree(workdir, ignore_errors=True)

    one()
    out.write_text(json.dumps({"stats": stats, "findings": findings}, indent=1, default=str))
    return {"stats": stats, "findings": findings}


if __name__ == "__main__":  # pragma: no cover - the exploratory run
    import argparse

    ap = argparse.ArgumentParser(description="exploratory scene fuzz (see the module docstring)")
    ap.add_argument("--examples", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--limit", type=float, default=20.0)
    ap.add_argument("--scenes", default=",".join(ALL_SCENES))
    ap.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "mechgen-fuzz-findings.json")
    ns = ap.parse_args()
    with contextlib.suppress(OSError):
        os.nice(15)
    result = explore(ns.examples, ns.seed, ns.out, tuple(ns.scenes.split(",")), ns.limit)
    print(json.dumps(result["stats"]))
