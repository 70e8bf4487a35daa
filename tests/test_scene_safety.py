"""A scene is data (issue 33): it cannot make mechgen connect anywhere or run code, the outputs write only
what the user named, as regular files, data files are streamed and never echoed, no event-driven run is silently
wrong, every run is bounded, and concurrent first runs build once.

Each probe of the issue is a test here: a hostile scene or flag ends with the stated exit code, one message naming
the file or flag and the key, no traceback, no stray file, and (for schedulers) no connection attempted at all:
``socket.socket.connect`` is replaced by a recorder, so a test proves that nothing was dialled, not that nothing
answered. The one test that connects starts its own Dask scheduler on the loopback and closes it.
"""
from __future__ import annotations

import json
import math
import os
import re
import socket
import stat
from pathlib import Path

import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError, SceneError

SWEEP = ('model = "laval_rotor"\n[[analysis]]\nname = "g"\nkind = "sweep"\nover = {{ Omega = [0.0, 1.0, 2.0] }}\n'
         'analysis = {{ kind = "stability" }}\nprogress = false\n{extra}\n')
#: addresses a scene named in the probe: a hostile scheduler, a port probe, and the ones that ended in tracebacks
HOSTILE_SCHEDULERS = ["tcp://127.0.0.1:8786", "tcp://203.0.113.7:8786", "inproc://x", "tls://127.0.0.1:8786",
                      "tcp://127.0.0.1", "file:///etc/passwd"]


@pytest.fixture
def dialled(monkeypatch) -> list:
    """Every address a socket of this process tries to connect to (none is let through)."""
    calls: list = []

    def refuse(self, address):
        calls.append(address)
        raise ConnectionRefusedError("test: no connection may be attempted")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket.socket, "connect_ex", refuse)
    return calls


def _run(argv, capsys) -> tuple[int, str]:
    code = main(argv)
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    return code, err


# ----------------------------------------------------------------------------- item 1: schedulers


@pytest.mark.parametrize("address", HOSTILE_SCHEDULERS)
def test_a_scene_cannot_name_a_scheduler(tmp_path, capsys, dialled, address):
    """executor = "dask" with a scheduler in the file is refused at load, exit 2 at the key, nothing dialled."""
    scene = tmp_path / "hostile.toml"
    scene.write_text(SWEEP.format(extra=f'executor = "dask"\nscheduler = "{address}"'))
    code, err = _run(["run", str(scene), "--backend", "numpy"], capsys)
    assert code == 2
    assert "hostile.toml" in err and "analysis[1].scheduler" in err and "--scheduler" in err, err
    assert dialled == []


def test_a_scene_dict_cannot_name_a_scheduler(dialled):
    """A scene given to mechgen.run as a dict is a scene too: the scheduler= argument is the Python way."""
    scene = {"model": "laval_rotor", "analysis": [
        {"name": "g", "kind": "sweep", "executor": "dask", "scheduler": "tcp://127.0.0.1:8786",
         "over": {"Omega": [0.0, 1.0]}, "analysis": {"kind": "stability"}}]}
    with pytest.raises(SceneError) as info:
        mechgen.run(scene)
    assert info.value.key == "analysis[1].scheduler" and "scheduler=" in str(info.value)
    assert dialled == []


@pytest.mark.parametrize("address", ["inproc://x", "tls://127.0.0.1", "tcp://127.0.0.1", "file:///etc/passwd",
                                     "tcp://127.0.0.1:99999", "tcp://user@127.0.0.1:8786", "tcp://a b:1",
                                     "tcp://127.0.0.1:8786/path", "localhost:8786", "x" * 400])
def test_the_scheduler_flag_is_checked_before_anything_connects(tmp_path, capsys, dialled, address):
    scene = tmp_path / "ok.toml"
    scene.write_text(SWEEP.format(extra='executor = "dask"'))
    code, err = _run(["run", str(scene), "--backend", "numpy", "--scheduler", address], capsys)
    assert code == 2 and "--scheduler" in err and "tcp://host:port" in err, err
    assert len(err) < 600  # a 400-character value is not echoed whole
    assert dialled == []


def test_a_scheduler_flag_for_a_scene_without_dask_is_refused(tmp_path, capsys, dialled):
    scene = tmp_path / "serial.toml"
    scene.write_text(SWEEP.format(extra=""))
    code, err = _run(["run", str(scene), "--backend", "numpy", "--scheduler", "tcp://127.0.0.1:8786"], capsys)
    assert code == 2 and "scheduler" in err and 'executor = "dask"' in err, err
    assert dialled == []


def test_python_scheduler_argument_is_checked(dialled):
    """The scheduler= argument of the Python functions is the user's choice, and still checked before use."""
    from mechgen.runtime.core.sweep import SweepExecutor

    system = mechgen.compile("laval_rotor", free=["Omega"], backend="numpy")
    with pytest.raises(InputError) as info:
        mechgen.sweep(system, "stability", {"Omega": [0.0, 1.0]}, executor="dask", scheduler="inproc://x")
    assert "scheduler" in info.value.key and "tcp://" in info.value.expected
    with pytest.raises(InputError) as info:
        SweepExecutor("dask", scheduler="file:///etc/passwd")
    assert info.value.key == "scheduler"
    assert dialled == []


def test_dask_configuration_address_is_checked(dialled):
    """Dask's own scheduler-address setting (DASK_SCHEDULER_ADDRESS) is the environment's choice: honoured,
    and checked before the first point runs."""
    dask = pytest.importorskip("dask")
    pytest.importorskip("distributed")
    from mechgen.runtime.core.sweep import SweepExecutor, sweep_points

    ran = []
    with dask.config.set({"scheduler-address": "inproc://x"}):
        with pytest.raises(InputError) as info:
            sweep_points(ran.append, [1.0, 2.0, 3.0], executor=SweepExecutor("dask"), progress=False)
    assert info.value.key == "DASK_SCHEDULER_ADDRESS" and ran == []
    assert dialled == []


def test_the_scheduler_flag_runs_on_the_users_scheduler(tmp_path, capsys):
    """--scheduler at a running scheduler (started here, loopback) gives the serial numbers bit for bit."""
    distributed = pytest.importorskip("distributed")
    scene = tmp_path / "grid.toml"
    scene.write_text(SWEEP.format(extra='executor = "dask"').replace("[0.0, 1.0, 2.0]", "[0.0, 500.0, 1000.0, 1500.0]"))
    serial = mechgen.run({**_toml(scene), "analysis": [{**_toml(scene)["analysis"][0], "executor": "serial"}]})
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, silence_logs=40) as cluster:
        out = tmp_path / "out.json"
        code, err = _run(["run", str(scene), "--scheduler", cluster.scheduler_address, "--json", str(out)], capsys)
    assert code == 0, err
    import json

    got = json.loads(out.read_text())["analyses"][0]["outputs"]
    assert got["executor"] == "dask"
    assert got["frequencies"] == serial["analyses"][0]["outputs"]["frequencies"]


def _toml(path: Path) -> dict:
    import tomllib

    return tomllib.loads(path.read_text())


# ----------------------------------------------------------------------------- item 2: output targets

SMALL = ('model = "spring_pendulum"\n[[analysis]]\nname = "eq"\nkind = "steady"\nguess = { r = 1.0 }\n'
         '[[analysis]]\nname = "small"\nkind = "modes"\nabout = "eq"\n')


@pytest.fixture
def small(tmp_path) -> Path:
    scene = tmp_path / "sp.toml"
    scene.write_text(SMALL)
    return scene


def _nodes(folder: Path) -> dict[str, Path]:
    """A FIFO, a socket and (as root) a character device equal to /dev/null, all made here: never the
    system's own nodes."""
    folder.mkdir(exist_ok=True)
    made = {"FIFO": folder / "fifo.json"}
    os.mkfifo(made["FIFO"])
    sock = socket.socket(socket.AF_UNIX)
    made["socket"] = folder / "sock.json"
    sock.bind(str(made["socket"]))
    sock.close()
    if os.geteuid() == 0:
        made["character device"] = folder / "null.json"
        os.mknod(made["character device"], stat.S_IFCHR | 0o666, os.makedev(1, 3))
    return made


def _mode(path: Path) -> int:
    return stat.S_IFMT(os.lstat(path).st_mode)


def test_json_never_replaces_a_device_fifo_or_socket(tmp_path, small, capsys):
    """--json onto a node that is not a regular file is refused before anything runs, and the node stays."""
    for what, node in _nodes(tmp_path / "nodes").items():
        before = _mode(node)
        code, err = _run(["run", str(small), "--json", str(node)], capsys)
        assert code == 2 and "--json" in err and what in err, (what, err)
        assert _mode(node) == before, what
    assert not [p for p in (tmp_path / "nodes").iterdir() if p.name.startswith(".tmp")]


def test_json_replaces_a_link_and_leaves_its_target(tmp_path, small, capsys):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    link = tmp_path / "out.json"
    link.symlink_to(victim)
    code, err = _run(["run", str(small), "--json", str(link)], capsys)
    assert code == 0, err
    assert victim.read_text() == "keep me" and not link.is_symlink() and '"analyses"' in link.read_text()


def test_plot_never_follows_a_link_planted_in_the_folder(tmp_path, small, capsys):
    """A link at a figure's name inside --plot DIR is replaced by the figure; its target is untouched."""
    pytest.importorskip("matplotlib")
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    plots = tmp_path / "plots"
    plots.mkdir()
    planted = plots / "sp_small_shapes.png"
    planted.symlink_to(victim)
    code, err = _run(["run", str(small), "--plot", str(plots)], capsys)
    assert code == 0, err
    assert victim.read_text() == "keep me"
    assert not planted.is_symlink() and planted.read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in plots.iterdir()) == ["sp_small.png", "sp_small_shapes.png"]  # no stray file


def test_plot_refuses_a_node_at_a_figure_name(tmp_path, small, capsys):
    """A FIFO (or a folder) holding a figure's name is refused at --plot, not opened (a FIFO would block)."""
    pytest.importorskip("matplotlib")
    plots = tmp_path / "plots"
    plots.mkdir()
    os.mkfifo(plots / "sp_small.png")
    (plots / "sp_small_shapes.png").mkdir()
    code, err = _run(["run", str(small), "--plot", str(plots)], capsys)
    assert code == 2 and "--plot" in err and ("FIFO" in err or "is a folder" in err), err
    assert stat.S_ISFIFO(os.lstat(plots / "sp_small.png").st_mode)
    assert sorted(p.name for p in plots.iterdir()) == ["sp_small.png", "sp_small_shapes.png"]


@pytest.mark.parametrize("flag", ["--json", "--plot"])
def test_an_overlong_name_is_refused_at_the_flag(tmp_path, small, capsys, flag):
    for path in (tmp_path / ("x" * 300), tmp_path / ("y" * 300) / "out.json", Path("/" + "z/" * 2100)):
        code, err = _run(["run", str(small), flag, str(path)], capsys)
        assert code == 2 and flag in err and "long" in err, err
        assert len(err) < 800  # the name is not echoed whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sp.toml"]


# ----------------------------------------------------------------------------- item 4: data files

FIT = """model = "spring_pendulum"
[[analysis]]
name = "f"
kind = "fit"
parameters = ["K", "k"]
start = { K = 500.0, k = 50.0 }
data = "DATA"
observed = "R"
expression = "K + k * (d0 / d)"
constants = { d0 = 25.4 }
"""
SECRET = "root:x:0:0:root:/root:/bin/bash"


def _fit(tmp_path, data: str, capsys) -> tuple[int, str]:
    scene = tmp_path / "scenes" / "fit.toml"
    scene.parent.mkdir(exist_ok=True)
    scene.write_text(FIT.replace("DATA", data))
    return _run(["run", str(scene)], capsys)


def _ctx(tmp_path, rows: int = 10):
    from types import SimpleNamespace

    return SimpleNamespace(file=str(tmp_path / "s.toml"), limits={"rows": rows})


@pytest.mark.parametrize("where", ["absolute", "relative"])
def test_a_data_file_is_never_echoed(tmp_path, capsys, where):
    """A file that is not CSV data (a passwd-like file of the test's own, by an absolute or a ../ path): the
    message names the line and column and shows at most a 10-character excerpt of the one cell."""
    secret = tmp_path / "passwd"
    secret.write_text(SECRET + "\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n")
    code, err = _fit(tmp_path, str(secret) if where == "absolute" else "../passwd", capsys)
    assert code == 2 and "analysis[1].data" in err and "line 1" in err and "column 1" in err, err
    assert SECRET not in err and "root:x:0:0:r" not in err and "daemon" not in err, err


def test_cells_and_headers_are_excerpted(tmp_path, capsys):
    data = tmp_path / "scenes" / "d.csv"
    data.parent.mkdir()
    for text, words in [("d,R\n1,2\n3,topsecretvalue123\n", "'topsecretv'…"),
                        ("d,R,password_is_hunter2\n1,2,3\n4,5\n", "has 2 cells, the header 3"),
                        ("d,R\n1,2\n" + "x" * 2_000_000, "longer than")]:
        data.write_text(text)
        code, err = _fit(tmp_path, "d.csv", capsys)
        assert code == 2 and words in err and "line 3" in err, err
        assert "topsecretvalue" not in err and "hunter2" not in err and "xxxxxxxxxxx" not in err, err


def test_the_row_limit_is_checked_while_reading(tmp_path):
    """A 4 MB file of 10^6 rows against a limit of 10 rows: refused after reading a few lines, with a peak
    of well under the file's size (the whole file split into a list took 11 GiB for 250 MB)."""
    import tracemalloc

    from mechgen.analyses import fit_data

    big = tmp_path / "big.csv"
    big.write_bytes(b"d,R\n" + b"1,2\n" * 1_000_000)
    blank = tmp_path / "blank.csv"
    blank.write_bytes(b"d,R\n" + b"\n" * 4_000_000)
    for path, words in [(big, "more than 10 rows"), (blank, "more than 10020 lines")]:
        tracemalloc.start()
        with pytest.raises(SceneError) as info:
            fit_data.load(_ctx(tmp_path), "analysis[1].data", str(path))
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert words in str(info.value)
        assert peak < 1_000_000, peak  # bytes; the file is 4 MB


def test_folders_fifos_and_devices_are_named_as_what_they_are(tmp_path):
    from mechgen.analyses import fit_data

    (tmp_path / "folder.csv").mkdir()
    os.mkfifo(tmp_path / "fifo.csv")
    cases = {"folder.csv": "is a folder", "fifo.csv": "is a FIFO", "missing.csv": "not found"}
    if os.geteuid() == 0:  # a node of the test's own, equal to /dev/zero (endless zero bytes)
        os.mknod(tmp_path / "zero.csv", stat.S_IFCHR | 0o444, os.makedev(1, 5))
        cases["zero.csv"] = "is a character device"
    for name, words in cases.items():
        with pytest.raises(SceneError) as info:  # a FIFO without a writer must not block
            fit_data.load(_ctx(tmp_path), "analysis[1].data", str(tmp_path / name))
        assert words in str(info.value) and info.value.key == "analysis[1].data", (name, str(info.value))


# ----------------------------------------------------------------------------- item 6: model references

OSC = '''from mechgen import Model, Param
print("model says hello")
model = Model("osc_s33", doc="x'' = -k/m x")
model.params(Param("m", 1.0, "kg"), Param("k", 4.0, "N/m"))
model.coordinates("x")
model.kinetic(lambda q, v, p: p.m * v.x**2 / 2)
model.potential(lambda q, p: p.k * q.x**2 / 2)
'''


def _model_scene(tmp_path, ref: str) -> Path:
    scene = tmp_path / "m.toml"
    scene.write_text(f'model = "{ref}"\n[[analysis]]\nname = "m"\nkind = "modes"\n')
    return scene


@pytest.mark.parametrize("code_line", ["raise SystemExit(0)", "import sys; sys.exit()", "raise SystemExit('bye')"])
def test_a_model_that_exits_on_import_is_exit_2(tmp_path, capsys, code_line):
    (tmp_path / "quits.py").write_text(f'print("SECRET-PRINT")\n{code_line}\n')
    code = main(["run", str(_model_scene(tmp_path, "quits.py"))])
    out = capsys.readouterr()
    assert code == 2 and "quits.py" in out.err and "SystemExit" in out.err and "Traceback" not in out.err, out.err
    assert "SECRET-PRINT" not in out.out + out.err


def test_a_module_without_a_model_prints_nothing(tmp_path, capsys, monkeypatch):
    """package.module:attribute of a module that is not a model (as `this:model` printed the Zen of Python)."""
    (tmp_path / "chatty_s33.py").write_text('print("SECRET-PRINT")\nvalue = 1\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    code = main(["run", str(_model_scene(tmp_path, "chatty_s33:model"))])
    out = capsys.readouterr()
    assert code == 2 and "defines no Model" in out.err and "SECRET-PRINT" not in out.out + out.err, out


def test_a_models_own_prints_go_to_stderr(tmp_path, capsys):
    (tmp_path / "osc_s33.py").write_text(OSC)
    code = main(["run", str(_model_scene(tmp_path, "osc_s33.py")), "--backend", "numpy"])
    out = capsys.readouterr()
    assert code == 0, out.err
    assert "model says hello" in out.err and "model says hello" not in out.out


# ----------------------------------------------------------------------------- item 3: unnoticed crossings

BALL = str(Path(__file__).resolve().parent / "models" / "bouncing_ball.py")
G = 9.81  # the test model's default g (m/s^2)


def _drop(y0: float, cor: float, loop: str, **extra) -> dict:
    return mechgen.run({"model": BALL, "params": {"cor": cor}, "analysis": [
        {"name": "drop", "kind": "simulate", "method": "DOP853", "t_end": 10.0, "q0": {"y": y0}, "loop": loop,
         "progress": False, **extra}]})


@pytest.mark.parametrize("loop", ["python", "c"])
def test_a_ball_at_rest_on_the_floor_never_falls_through_silently(loop):
    """y = 0, y' = 0: the floor guard (falling) has g = g_t = 0; the ball leaves it downwards at once."""
    with pytest.raises(mechgen.ConvergenceError) as info:
        _drop(0.0, 0.5, loop)
    assert "guard floor of mode flight" in str(info.value) and "t = 0 and" in str(info.value)


@pytest.mark.parametrize("loop", ["python", "c"])
def test_a_zeno_accumulation_with_a_huge_zeno_limit_is_stopped_at_the_accumulation_time(loop):
    """The probe's case: zeno_events so large that the Zeno test never fires. The impacts accumulate at
    T = t1 (1 + e) / (1 - e), t1 = sqrt(2 h / g) (the model's docstring); there the resets no longer lift the
    ball and it left the floor downwards (3 596 J of kinetic energy at t = 10 s, exit 0, before the fix). Now the
    run ends there with exit 1 naming the guard and the time; the time agrees with T to 1e-6 relative (the last
    located impacts are within the integrator's tolerance of the closed form's geometric sequence)."""
    import re

    h, e = 1.0, 0.5
    T = math.sqrt(2 * h / G) * (1 + e) / (1 - e)
    with pytest.raises(mechgen.ConvergenceError) as info:
        _drop(h, e, loop, zeno_events=100_000, max_events=100_000)
    text = str(info.value)
    assert "guard floor of mode flight" in text, text
    t_hi = float(re.search(r"between t = \S+ and (\S+) \(", text).group(1))
    assert abs(t_hi - T) < 1e-6 * T, (t_hi, T)


def test_event_limits_beyond_the_budget_are_refused_up_front(tmp_path, capsys):
    (tmp_path / "ball.py").write_text(Path(BALL).read_text())
    scene = tmp_path / "ball.toml"
    base = 'model = "ball.py"\n[[analysis]]\nname = "d"\nkind = "simulate"\nt_end = 10.0\nq0 = { y = 1.0 }\n'
    for extra, key in [("zeno_events = 1_000_000_000\nmax_events = 1_000_000_000\n", "analysis[1].max_events"),
                       ("zeno_events = 20_000\n", "analysis[1].zeno_events")]:
        scene.write_text(base + extra)
        code, err = _run(["run", str(scene)], capsys)
        assert code == 2 and key in err and "ball.toml" in err, err


# ----------------------------------------------------------------------------- item 7: one build per key

def _first_run(args: tuple) -> int:
    """In a worker process: compile a model of the test's own into an empty cache; its compiler runs."""
    root, model_file = args
    os.environ["MECHGEN_CACHE"] = root
    import mechgen as mg
    from mechgen.codegen.build import STATS

    system = mg.compile(model_file, backend="c")
    assert system.n == 1
    from mechgen.runtime.integration.events_c import loop_library

    loop_library()  # a runtime loop library (hybrid_loop.c), built through mechgen.buildlock.load_shared_once
    return STATS["compile"]


def test_concurrent_first_runs_derive_and_compile_once(tmp_path):
    """Four processes compile one model, and load the C event loop, into one empty cache at once: the build
    locks let one derive and compile each; the others wait, then load its cache entries."""
    import multiprocessing

    from mechgen.codegen.build import find_compiler

    if find_compiler() is None:
        pytest.skip("no C compiler")
    (tmp_path / "osc_s33.py").write_text(OSC)
    args = (str(tmp_path / "cache"), str(tmp_path / "osc_s33.py"))
    with multiprocessing.get_context("spawn").Pool(4) as pool:
        runs = pool.map(_first_run, [args] * 4)
    # one compile each: the kernels and the kernel caller (under the request's lock), the loop library (under its
    # own); without the locks every process compiled all three: [3, 3, 3, 3]
    assert sum(runs) == 3, runs
    assert not list((tmp_path / "cache" / "locks").iterdir())


def test_a_lock_left_by_a_killed_process_is_broken(tmp_path, monkeypatch):
    """A lock naming a process that no longer exists (a child started and reaped here) is broken at once; a
    lock of a live process (this one) is waited on (here the wait is cut to 0.2 s); an empty lock whose writer
    died before writing it is broken after EMPTY_SECONDS."""
    import subprocess
    import time

    from mechgen import buildlock

    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "cache"))
    dead = subprocess.Popen(["true"])
    dead.wait()
    path = buildlock.lock_path("k1")
    path.write_text(json.dumps({"pid": dead.pid, "host": socket.gethostname(), "time": time.time()}))
    started = time.monotonic()
    with buildlock.held("k1") as mine:
        assert mine and json.loads(path.read_text())["pid"] == os.getpid()
    assert time.monotonic() - started < 1 and not path.exists()
    live = buildlock.lock_path("k2")
    live.write_text(json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "time": time.time()}))
    started = time.monotonic()
    assert buildlock.acquire("k2", wait=0.2) is None and live.exists()
    assert 0.2 <= time.monotonic() - started < 2
    empty = buildlock.lock_path("k3")
    empty.write_text("")
    os.utime(empty, (time.time() - 2 * buildlock.EMPTY_SECONDS,) * 2)
    lock = buildlock.acquire("k3", wait=0.2)
    assert lock == empty and json.loads(empty.read_text())["pid"] == os.getpid()
    buildlock.release(lock)
    assert sorted(p.name for p in path.parent.iterdir()) == ["k2"]  # nothing stray


# ----------------------------------------------------------------------------- item 5: edge values, singular modes

def test_a_parameter_at_the_edge_of_the_float_range_is_named(capsys):
    """k_r = DBL_MAX: the stiffness matrix overflows; exit 2 at the flag that set it, not a ValueError traceback."""
    scene = Path(__file__).resolve().parent.parent / "scenes" / "laval_rotor.toml"
    code, err = _run(["run", str(scene), "--backend", "numpy", "--set", "k_r=1.7976931348623157e308"], capsys)
    assert code == 2 and "'--set k_r'" in err and "edge of the floating-point range" in err, err


@pytest.mark.parametrize("loop", ["python", "c"])
def test_a_zero_mass_in_a_hybrid_mode_is_diagnosed(tmp_path, loop):
    """m = 0 in the ball's only mode (its bound positive=True removed): M = 0 is singular where the mode starts;
    a ConvergenceError naming the coordinate, in both loops (the Python loop raised a bare LinAlgError)."""
    (tmp_path / "ball0.py").write_text(Path(BALL).read_text().replace(', positive=True), Param("g"',
                                                                      '), Param("g"', 1))
    with pytest.raises(mechgen.ConvergenceError) as info:
        mechgen.run({"model": str(tmp_path / "ball0.py"), "params": {"m": 0.0}, "analysis": [
            {"name": "d", "kind": "simulate", "method": "DOP853", "t_end": 1.0, "q0": {"y": 1.0}, "loop": loop}]})
    assert "no inertia along coordinate 'y'" in str(info.value), str(info.value)


TWO_MODE = '''"""A ball in flight (mass m) landing into mode 'glued', whose added kinetic energy extra/2 y'^2 makes the mass
m + extra: zero for extra = -m, a singular M in that mode only."""
from mechgen import Model, Param

model = Model("test_two_mode_mass", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("g", 9.81, "m/s^2", positive=True), Param("extra", 0.0, "kg"))
model.coordinates("y")
flight = model.mode("flight")
glued = model.mode("glued")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y


@glued.kinetic
def glued_kinetic(v, p):
    return p.extra / 2 * v.y**2


@flight.guard(to="glued", direction="falling")
def floor(q):
    return q.y
'''


@pytest.mark.parametrize("loop", ["python", "c"])
def test_a_zero_mass_in_one_mode_only_names_that_mode(tmp_path, capsys, loop):
    """M = 0 only in the mode entered at the first landing (t1 = sqrt(2 h / g) = 0.1428 s from h = 0.1 m): exit 1
    naming that mode, the coordinate and M = dr/da (the tangent kernel), in both loops (the compiled loop named the
    mode it left, flight, and explained nothing)."""
    (tmp_path / "two_mode.py").write_text(TWO_MODE)
    scene = tmp_path / "glued.toml"
    scene.write_text('model = "two_mode.py"\n[params]\nextra = -1.0\n[[analysis]]\nname = "d"\nkind = "simulate"\n'
                     f'method = "DOP853"\nt_end = 1.0\nq0 = {{ y = 0.1 }}\nloop = "{loop}"\n')
    code, err = _run(["run", str(scene)], capsys)
    message = err.strip().splitlines()[-1]
    assert code == 1 and message.startswith("mechgen: ConvergenceError:"), err
    assert "in mode glued" in message and "M = dr/da is zero" in message and "coordinate 'y'" in message, message
    t1 = math.sqrt(2 * 0.1 / 9.81)
    assert f"t = {t1:.6g}" in message, message  # the landing time, closed form


def test_every_kind_has_a_wall_time_budget():
    """max_seconds is a key of every kind, and a kind whose runner has no budget of its own (here a test kind
    that computes for 30 s) is stopped by the backstop at max_seconds x 1.1 + 2 s, exit 1 naming the key."""
    import time

    from mechgen.analyses import registry, summary
    from mechgen.analyses.public import analysis
    from mechgen.runtime.core.budget import BudgetExceeded

    assert all("max_seconds" in registry.get(k).schema for k in registry.kinds())

    def endless(system, options, context):
        stop = time.monotonic() + 30
        while time.monotonic() < stop:
            sum(range(1000))
        return {}

    registry.register(registry.AnalysisKind("endless_s33", {}, endless, lambda o, *, internal: set(), summary.lines))
    try:
        system = mechgen.compile("spring_pendulum", backend="numpy")
        started = time.monotonic()
        with pytest.raises(BudgetExceeded) as info:
            analysis("endless_s33", system, max_seconds=0.3)
        assert info.value.key == "max_seconds" and "endless_s33" in str(info.value)
        assert 2.3 < time.monotonic() - started < 5  # 0.3 x 1.1 + 2 s (BACKSTOP_GRACE, BACKSTOP_MARGIN)
    finally:
        registry.unregister("endless_s33")


SCENES_DIR = Path(__file__).resolve().parent.parent / "scenes"


@pytest.mark.parametrize("scene, analysis, limit, unknowns", [
    ("beck_column.toml", "at_P", "1GiB", 4 * 100_000),     # hermite: 2 unknowns per node, refined at 2N
    ("beam_modes.toml", "modes", "0.9GiB", 4 * 100_000)])  # quintic: 4 unknowns per element, no refinement
def test_a_huge_sparse_eigenproblem_is_refused_before_it_starts(tmp_path, capsys, monkeypatch, scene, analysis,
                                                                limit, unknowns):
    """N = 10^5 with count (the sparse shift-invert path): SPARSE_BYTES_PER_UNKNOWN x the unknowns of the largest
    solve is refused at the flag that set N, before anything is assembled (the discretisation's own estimate
    passes under this limit); at N = 10^6 Beck's column ran 10 minutes past 3.4 GiB."""
    import time

    from mechgen.runtime.linear.stability import SPARSE_BYTES_PER_UNKNOWN

    text = (SCENES_DIR / scene).read_text().split("\n[[analysis]]\nname = ")
    (tmp_path / scene).write_text(text[0] + "".join("\n[[analysis]]\nname = " + t for t in text[1:]
                                                     if t.startswith(f'"{analysis}"')))
    monkeypatch.setenv("MECHGEN_MEMORY_LIMIT", limit)
    started = time.monotonic()
    code, err = _run(["run", str(tmp_path / scene), "--set", "N=100000"], capsys)
    message = err.strip().splitlines()[-1]
    assert code == 2 and "at key '--set N'" in message and f"of {unknowns} unknowns" in message, message
    assert f"{SPARSE_BYTES_PER_UNKNOWN * unknowns / 2**30:.3g} GiB" in message, message
    assert time.monotonic() - started < 30


def test_a_hybrid_event_store_past_the_memory_is_refused(tmp_path, capsys, monkeypatch):
    """max_events = max_steps = 10^9 (the step bound allows it): 10^9 x (EVENT_BYTES + 3 x 8 x 2) bytes of stored
    events are refused at the key up front under a 1 GiB limit; the default 10^4 runs."""
    from mechgen.analyses.simulate_hybrid import EVENT_BYTES

    scene = tmp_path / "ball.toml"
    body = (f'model = "{BALL}"\n[[analysis]]\nname = "d"\nkind = "simulate"\nmethod = "DOP853"\nt_end = 1.0\n'
            'q0 = {{ y = 1.0 }}\n{extra}')
    monkeypatch.setenv("MECHGEN_MEMORY_LIMIT", "1GiB")
    # max_seconds raised so that the event count passes the time estimate (10^9 x EVENT_SECONDS = 10^4 s)
    scene.write_text(body.format(extra="max_events = 1000000000\nmax_steps = 1000000000\nmax_seconds = 100000\n"))
    code, err = _run(["run", str(scene)], capsys)
    assert code == 2 and "at key 'max_events'" in err, err
    assert f"{10**9 * (EVENT_BYTES + 48) / 2**30:.3g} GiB" in err, err
    scene.write_text(body.format(extra=""))
    assert _run(["run", str(scene)], capsys)[0] == 0


def periodic_scene() -> str:
    """scenes/stick_slip_element.toml up to and including its hybrid ``periodic`` analysis (its first), so that keys
    appended to the text land in that analysis's table."""
    head, periodic = (SCENES_DIR / "stick_slip_element.toml").read_text().split("[[analysis]]")[:2]
    assert 'kind = "periodic"' in periodic
    return head + "[[analysis]]" + periodic.rstrip() + "\n"


@pytest.mark.parametrize("extra, key", [("max_events = 1000000000", "analysis[1].max_events"),
                                        ("zeno_events = 20000", "analysis[1].zeno_events"),
                                        ("max_events = 1000000000\nmax_steps = 1000000000\nmax_seconds = 100000",
                                         "max_events")])
def test_periodic_event_limits_are_bounded_up_front(tmp_path, capsys, extra, key):
    """The hybrid periodic kind refuses max_events above its step budget (default 10^5 steps) and zeno_events above
    max_events at load, as simulate does, and an event store past the memory before it runs."""
    scene = tmp_path / "loop.toml"
    scene.write_text(periodic_scene() + extra + "\n")
    code, err = _run(["run", str(scene)], capsys)
    assert code == 2 and f"at key '{key}'" in err, err


def test_periodic_keeps_running_with_few_events(tmp_path, capsys):
    """max_events = 50 alone is not refused for the default zeno_events (100): only a zeno_events the scene wrote
    is compared with max_events (the loop has a handful of events a period)."""
    scene = tmp_path / "loop.toml"
    scene.write_text(periodic_scene() + "max_events = 50\n")
    code, err = _run(["run", str(scene)], capsys)
    assert code == 0 or "max_events" in err, err


@pytest.mark.parametrize("scene, per_element", [("rod_tip_load.toml", 48_000), ("rod_dynamics.toml", 32_000)])
def test_a_huge_rod_is_refused_before_it_starts(tmp_path, capsys, monkeypatch, scene, per_element):
    """elements = 100 000 under a 2 GiB memory limit: the estimate (the measured bytes per element times the
    elements) is refused at the key up front, in seconds (it took 1.7 GiB within 15 s and ran on)."""
    import time

    text = (Path(__file__).resolve().parent.parent / "scenes" / scene).read_text()
    text = re.sub(r"elements = \d+", "elements = 100000", text)
    (tmp_path / scene).write_text(text)
    monkeypatch.setenv("MECHGEN_MEMORY_LIMIT", "2GiB")
    started = time.monotonic()
    code, err = _run(["run", str(tmp_path / scene)], capsys)
    assert code == 2 and "'elements'" in err and f"{100_000 * per_element / 2**30:.3g} GiB" in err, err
    assert time.monotonic() - started < 30


# ------------------------------------------------------------- item 5: wall time estimated before the work starts


def _one_analysis(tmp_path, scene: str, analysis: str, extra: str = "") -> Path:
    """A copy of a shipped scene holding its analysis ``analysis`` alone, with ``extra`` lines in that table."""
    text = (SCENES_DIR / scene).read_text().split("\n[[analysis]]\nname = ")
    kept = [t for t in text[1:] if t.startswith(f'"{analysis}"')]
    assert len(kept) == 1, scene
    path = tmp_path / scene
    path.write_text(text[0] + "\n[[analysis]]\nname = " + kept[0].rstrip() + "\n" + extra)
    return path


def test_a_sparse_eigenproblem_past_its_wall_time_is_refused_up_front(tmp_path, capsys):
    """Beck's column with count at N = 2 x 10^5 and max_seconds = 10: sparse_seconds (c n^(4/3) per solve,
    measured) for the solve of 4 x 10^5 unknowns and its 2N check is about 93 s, refused at the flag that set N
    before anything is factorised (the solve itself would take about 2 minutes here); refine = false drops the 2N
    solve from the estimate (25 s, still refused)."""
    import time

    from mechgen.runtime.linear.stability import sparse_seconds

    n = 4 * 10**5  # hermite: 2 unknowns per node
    for extra, seconds in [("", sparse_seconds(n, general=True) + sparse_seconds(2 * n, general=True)),
                           ("refine = false\n", sparse_seconds(n, general=True))]:
        scene = _one_analysis(tmp_path, "beck_column.toml", "at_P", "max_seconds = 10\n" + extra)
        started = time.monotonic()
        code, err = _run(["run", str(scene), "--set", "N=200000"], capsys)
        elapsed = time.monotonic() - started
        message = err.strip().splitlines()[-1]
        assert code == 2 and "at key '--set N'" in message and "max_seconds = 10" in message, message
        assert f"max_seconds raised above {seconds:.3g}" in message, message
        assert elapsed < 5, elapsed  # refused before assembly and factorisation (about 0.5 s here)


def test_a_sparse_eigenproblem_within_its_wall_time_runs(tmp_path, capsys):
    """Beck's column at N = 1000 (2000 unknowns, the sparse path above 400; larger N meet the round-off bound,
    tests/test_roundoff_bound.py): the estimate (about 0.1 s) is far below the max_seconds = 10 given, and the run
    ends with a verdict (exit 0): the estimate refuses nothing it should run."""
    from mechgen.runtime.linear.stability import sparse_seconds

    assert sparse_seconds(2000, general=True) + sparse_seconds(4000, general=True) < 0.2
    scene = _one_analysis(tmp_path, "beck_column.toml", "at_P", "max_seconds = 10\n")
    code, err = _run(["run", str(scene), "--set", "N=1000"], capsys)
    assert code == 0, err


@pytest.mark.parametrize("scene, extra, least", [
    # 5 load steps (ceil(10 / 2)) x 10^5 elements x 40 us
    ("rod_tip_load.toml", "elements = 100000\nsteps = 10\nmax_seconds = 5\n", 5 * 10**5 * 4.0e-5),
    # 400 steps (t_end / dt) x 2 x 10^4 elements x 1.2 us (analyses.rod_dynamics.SOLVE_SECONDS)
    ("rod_dynamics.toml", "elements = 20000\nmax_seconds = 5\n", 400 * 2 * 10**4 * 1.2e-6)])
def test_a_rod_past_its_wall_time_is_refused_up_front(tmp_path, capsys, scene, extra, least):
    """The rods' least wall time (measured cost per element of a Newton iteration or solve, times the least count of
    them) above max_seconds is refused at 'elements' in well under a second, before any element is built."""
    import time

    text = re.sub(r"(elements|steps) = \d+\n", "", (SCENES_DIR / scene).read_text())
    (tmp_path / scene).write_text(text.rstrip() + "\n" + extra)
    started = time.monotonic()
    code, err = _run(["run", str(tmp_path / scene)], capsys)
    assert code == 2 and "at key 'elements'" in err and f"max_seconds raised above {least:.3g}" in err, err
    assert time.monotonic() - started < 5


@pytest.mark.parametrize("scene", ["rod_tip_load.toml", "rod_dynamics.toml", "rod_end_torque.toml"])
def test_the_shipped_rods_are_not_refused(scene, capsys):
    """The shipped rod scenes run (exit 0) under the default max_seconds: their estimates are far below it."""
    code, err = _run(["run", str(SCENES_DIR / scene)], capsys)
    assert code == 0, err


@pytest.mark.parametrize("extra, key", [
    ("zeno_events = 100000000\nmax_events = 100000000\nmax_steps = 100000000\n", "analysis[1].zeno_events"),
    ("max_events = 100000000\nmax_steps = 100000000\n", "analysis[1].max_events"),
    ("max_events = 1000000\nmax_steps = 1000000\nmax_seconds = 5\n", "analysis[1].max_events")])
def test_event_counts_past_the_wall_time_are_refused_at_load(tmp_path, capsys, extra, key):
    """10^8 events at EVENT_SECONDS (10 us, the compiled loop's measured 13-15 us on a bouncing ball rounded down)
    take at least 1000 s, more than max_seconds = 600: a Zeno limit or an event limit the budget cannot reach is
    refused at its key at load (zeno_events first: it is what would end a Zeno run); 10^6 under max_seconds = 5 too."""
    (tmp_path / "ball.py").write_text(Path(BALL).read_text())
    scene = tmp_path / "ball.toml"
    scene.write_text('model = "ball.py"\n[[analysis]]\nname = "d"\nkind = "simulate"\nt_end = 1.0\n'
                     'q0 = { y = 1.0 }\n' + extra)
    code, err = _run(["run", str(scene)], capsys)
    assert code == 2 and f"at key '{key}'" in err and "max_seconds" in err, err


def test_event_counts_within_the_wall_time_run(tmp_path, capsys):
    """max_events = 10^6 (at least 10 s of events, under the default 600 s) is accepted: the ball's run to
    t_end = 1 s (its one impact at t = 0.45 s, before the Zeno time 4.1 s) ends normally (exit 0)."""
    (tmp_path / "ball.py").write_text(Path(BALL).read_text())
    scene = tmp_path / "ball.toml"
    scene.write_text('model = "ball.py"\n[[analysis]]\nname = "d"\nkind = "simulate"\nt_end = 1.0\n'
                     'q0 = { y = 1.0 }\nmax_events = 1000000\nmax_steps = 1000000\n')
    code, err = _run(["run", str(scene)], capsys)
    assert code == 0, err


@pytest.mark.parametrize("exc", [MemoryError(), SystemError("SuperLU: out of memory"),
                                 ValueError("array must not contain infs or NaNs"), ZeroDivisionError("x")])
def test_a_runners_stray_numerical_exception_is_exit_1(exc, capsys, tmp_path):
    """What a runner raises from numpy/scipy (as SuperLU did under an address-space limit) is a ConvergenceError
    naming the analysis: exit 1, one message, no traceback."""
    from mechgen.analyses import registry, summary

    def failing(system, options, context):
        raise exc

    registry.register(registry.AnalysisKind("failing_s33", {}, failing, lambda o, *, internal: set(), summary.lines))
    try:
        scene = tmp_path / "f.toml"
        scene.write_text('model = "spring_pendulum"\n[[analysis]]\nname = "f"\nkind = "failing_s33"\n')
        code, err = _run(["run", str(scene), "--backend", "numpy"], capsys)
        assert code == 1 and "failing_s33 'f'" in err and type(exc).__name__ in err, err
    finally:
        registry.unregister("failing_s33")


def test_a_late_error_names_the_flag_that_decided_it(capsys):
    """The fuzz finding of this round: --set quadrature=1 makes stepped_rotor's quintic mass matrix singular,
    found at the internal key 'M' under one BLAS kernel and not at all under the other (a run that returned
    garbage); too few Gauss points are now refused before anything is assembled, at the flag that set them."""
    scene = Path(__file__).resolve().parent.parent / "scenes" / "stepped_rotor.toml"
    code, err = _run(["run", str(scene), "--set", "quadrature=1"], capsys)
    assert code == 2 and "--set quadrature = 1" in err and "under-integrate" in err, err


def test_a_kind_without_a_budget_of_its_own_stops_at_max_seconds(tmp_path, capsys):
    """A kind whose work has no budget of its own (a test kind computing for 20 s in Python, as an eigen-solve's
    reverse-communication loop does; Beck's column at N = 20 000 served until the sparse shift made it fast) is
    stopped by the backstop after 0.5 x 1.1 + 2 s with exit 1 naming the analysis and the key."""
    import time

    from mechgen.analyses import registry, summary

    def endless(system, options, context):
        stop = time.monotonic() + 20
        while time.monotonic() < stop:
            sum(range(1000))
        return {"done": 1.0}

    registry.register(registry.AnalysisKind("endless_s33", {}, endless, lambda o, *, internal: set(),
                                            summary.lines))
    (tmp_path / "endless.toml").write_text('model = "laval_rotor"\n[[analysis]]\nname = "at_P"\n'
                                           'kind = "endless_s33"\nmax_seconds = 0.5\n')
    started = time.monotonic()
    try:
        code, err = _run(["run", str(tmp_path / "endless.toml")], capsys)
    finally:
        registry.unregister("endless_s33")
    assert code == 1 and "'at_P'" in err and "'max_seconds'" in err, err
    assert time.monotonic() - started < 12
