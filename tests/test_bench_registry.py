"""The benchmark registry: `mechgen bench --list` names every suite, each names a runnable entry point, unknown
names are refused before anything runs, and `import mechgen.bench` loads no suite."""
import importlib
import inspect
import subprocess
import sys

from mechgen.bench import REGISTRY, SUITES
from mechgen.cli import main


def test_list_names_every_suite(capsys):
    assert main(["bench", "--list"]) == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert names == list(SUITES) == ["fpu", "beam", "rotor", "balloon", "startup", "impacts", "friction", "rods", "threads", "simulate", "orbits", "sweep", "multibody", "plane"]


def test_every_suite_names_an_entry_point_taking_out_and_quick():
    for suite in REGISTRY.values():
        fn = getattr(importlib.import_module(suite.module), suite.function)
        assert {"out", "quick"} <= set(inspect.signature(fn).parameters), suite.name


def test_unknown_suite_is_refused(tmp_path, capsys):
    assert main(["bench", "fpu", "nope", "--out", str(tmp_path)]) == 2
    assert "unknown benchmark 'nope'" in capsys.readouterr().err and not any(tmp_path.iterdir())


def test_importing_the_registry_loads_no_suite():
    code = "import sys, mechgen.bench; print(sorted(m for m in sys.modules if m.startswith(('numpy', 'mechgen.bench.'))))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
