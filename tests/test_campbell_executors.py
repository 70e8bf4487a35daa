"""The campbell analysis on the serial, local-process and Dask executors (issue 16 item 5).

References: the serial executor's numbers (each speed's eigen-solve depends only on that speed's
matrices, assembled in the driver for every executor, and the tracking runs in the driver on the same
candidates, so every executor must give the same floats, bit for bit), and ROSS 2.3.0's modal analysis
of its documented example rotor (benchmarks/ross_data/ross_reference.json, as tests/test_rotor_scenes.py)
at the diagram's end speeds. Dask is real: a LocalCluster on the loopback started by the run.
"""
from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError
from mechgen.runtime.core.sweep import SweepExecutor
from mechgen.runtime.linear.campbell import campbell, fit_speed_polynomial

pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "ross_example_rotor.toml"
ROSS = json.loads((ROOT / "benchmarks" / "ross_data" / "ross_reference.json").read_text())["rotors"]["example"]


def _campbell_scene(**keys) -> dict:
    """scenes/ross_example_rotor.toml with its campbell analysis only (50 speeds, 0 .. 1000 rad/s), plus ``keys``."""
    scene = tomllib.loads(SCENE.read_text())
    scene["analysis"] = [{**a, **keys} for a in scene["analysis"] if a["name"] == "campbell"]
    return scene


def _run(**keys) -> dict:
    return mechgen.run(_campbell_scene(**keys), backend="numpy")["analyses"][0]["outputs"]


def test_executors_give_the_serial_diagram_bit_for_bit_and_rosss_modes():
    runs = {ex: _run(executor=ex, workers=2) for ex in ("serial", "processes", "dask")}
    serial = runs["serial"]
    assert serial["method"] == "exact" and serial["exact_solves"] == 50
    for ex in ("processes", "dask"):
        out = runs[ex]
        assert out["executor"] == ex and out["method"] == "exact" and out["exact_solves"] == 50
        for key in ("speeds", "frequencies", "log_dec", "whirl", "critical_speeds"):
            assert out[key] == serial[key], (ex, key)  # bit for bit
    # ROSS's damped natural frequencies (lateral model) at the first and last speed: the tracked curves are a
    # permutation of the sorted modes there
    for row, speed in ((0, "0.0"), (-1, "1000.0")):
        np.testing.assert_allclose(sorted(serial["frequencies"][row]), ROSS["modal"][speed]["lateral_only"]["wd"][:8],
                                   rtol=1e-6)
    assert len(serial["critical_speeds"]) == 6


def test_public_campbell_takes_the_executor_keys():
    """mechgen.campbell(..., executor=...) on the Laval rotor (4 dofs, method auto: exact at every speed):
    the serial numbers, and the closed form omega_f,b = (+-Ip Omega + sqrt(Ip^2 Omega^2 + 4 Id k_r)) / (2 Id)
    of the tilts beside the translations' sqrt(k_t / m) (model docstring)."""
    system = mechgen.compile("laval_rotor", backend="numpy")
    over = {"Omega": [0.0, 250.0, 500.0, 750.0, 1000.0]}
    serial = mechgen.campbell(system, over=over, count=4)
    local = mechgen.campbell(system, over=over, count=4, executor="processes", workers=2)
    assert local.outputs["frequencies"] == serial.outputs["frequencies"]
    assert local.outputs["executor"] == "processes" and serial.outputs["executor"] == "serial"
    ip, i_d, k_r, k_t, m = 0.2, 0.1, 2.0e4, 4.0e5, 10.0
    for w, row in zip(over["Omega"], serial.outputs["frequencies"]):
        root = np.sqrt(ip**2 * w**2 + 4 * i_d * k_r)
        exact = sorted([(ip * w + root) / (2 * i_d), (-ip * w + root) / (2 * i_d), np.sqrt(k_t / m), np.sqrt(k_t / m)])
        np.testing.assert_allclose(sorted(row), exact, rtol=1e-10)


def test_reduced_method_is_refused_on_a_parallel_executor(tmp_path, capsys):
    path = tmp_path / "reduced.toml"
    scene = _campbell_scene(method="reduced", executor="dask")
    text = SCENE.read_text().split("[[analysis]]")[0]
    path.write_text(text + '[[analysis]]\nname = "c"\nkind = "campbell"\nover = { Omega = [0.0, 500.0, 1000.0] }\n'
                    'method = "reduced"\nexecutor = "dask"\n')
    assert main(["run", str(path), "--backend", "numpy"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "analysis[1].executor" in err and "reduced" in err
    with pytest.raises(InputError, match="executor"):
        mechgen.run(scene, backend="numpy")
    # workers > 1 without an executor means processes: refused at workers
    path.write_text(text + '[[analysis]]\nname = "c"\nkind = "campbell"\nover = { Omega = [0.0, 500.0] }\n'
                    'method = "reduced"\nworkers = 2\n')
    assert main(["run", str(path), "--backend", "numpy"]) == 2
    assert "analysis[1].workers" in capsys.readouterr().err
    # a scheduler without executor = "dask" is refused as in sweep
    path.write_text(text + '[[analysis]]\nname = "c"\nkind = "campbell"\nover = { Omega = [0.0, 500.0] }\n'
                    'scheduler = "tcp://127.0.0.1:1"\n')
    assert main(["run", str(path), "--backend", "numpy"]) == 2
    assert "analysis[1].scheduler" in capsys.readouterr().err


def test_runtime_campbell_refuses_reduced_on_dask_and_runs_auto_exact():
    """A 2-dof gyroscopic system M = I, G = Omega [[0, 1/2], [-1/2, 0]], K = I: with z = x + i y,
    z'' - i Omega/2 z' + z = 0, so the whirl frequencies are sqrt(Omega^2/16 + 1) +- Omega/4."""
    G1 = np.array([[0.0, 0.5], [-0.5, 0.0]])

    def mats(w: float) -> dict:
        return {"M": np.eye(2), "C": w * G1, "K": np.eye(2)}

    speeds = np.linspace(0.0, 2.0, 6)
    poly = fit_speed_polynomial(mats, speeds[0], speeds[-1])
    with pytest.raises(InputError, match="executor"):
        campbell(poly, speeds, 2, method="reduced", executor=SweepExecutor("processes", 2), x_index=[0],
                 y_index=[1])
    res = campbell(poly, speeds, 2, executor=SweepExecutor("processes", 2), x_index=[0], y_index=[1])
    assert res.method == "exact"
    for w, row in zip(speeds, res.frequencies):
        root = np.sqrt(w**2 / 16 + 1)
        np.testing.assert_allclose(sorted(row), sorted([root - w / 4, root + w / 4]), rtol=1e-12)


def test_an_input_error_from_a_worker_keeps_its_key():
    import pickle

    from mechgen.errors import SceneError

    err = pickle.loads(pickle.dumps(SceneError("bad", file="a.toml", key="analysis[1].count", expected="1")))
    assert type(err) is SceneError and (err.file, err.key, err.expected) == ("a.toml", "analysis[1].count", "1")
    assert str(err) == "in a.toml at key 'analysis[1].count': bad; expected 1."
