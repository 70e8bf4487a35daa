"""The package as users and packagers see it (issue 31): license and metadata, the version everywhere it is
printed, the versions a run records, and the commands that need a source checkout refusing without one."""
import json
import re
import sys
from importlib import metadata
from pathlib import Path

import pytest

import mechgen
from mechgen.cli import main
from mechgen.version import versions

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]


def test_license_is_declared_and_shipped():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "BSD-3-Clause"
    assert "BSD 3-Clause License" in (ROOT / "LICENSE").read_text()
    assert project["license-files"] == ["LICENSE"]
    assert {"Documentation", "Source", "Issues"} <= set(project["urls"])
    assert project["authors"] and project["keywords"] and project["classifiers"]


def test_version_agrees_across_package_citation_and_changelog():
    assert mechgen.__version__ == metadata.version("mechgen")
    cff = (ROOT / "CITATION.cff").read_text()
    assert re.search(rf'^version: "{re.escape(mechgen.__version__)}"$', cff, re.M)
    assert f"## [{mechgen.__version__}]" in (ROOT / "CHANGELOG.md").read_text()


def test_version_flag_prints_the_versions(capsys):
    assert main(["--version"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"mechgen {mechgen.__version__} (")
    for name in ("numpy", "scipy", "sympy", "casadi"):
        assert f"{name} {metadata.version(name)}" in line


def test_a_scene_json_records_the_versions_that_produced_it(tmp_path, capsys):
    target = tmp_path / "out.json"
    assert main(["run", str(ROOT / "scenes" / "spring_pendulum.toml"), "--json", str(target)]) == 0
    recorded = json.loads(target.read_text())["versions"]
    assert recorded == versions()
    assert set(recorded) == {"mechgen", "python", "numpy", "scipy", "sympy", "casadi"}
    # against the installed distributions' metadata, read independently of mechgen.version
    assert all(recorded[name] == metadata.version(name) for name in ("numpy", "scipy", "sympy", "casadi"))
    assert recorded["python"] == sys.version.split()[0] and recorded["mechgen"] == metadata.version("mechgen")


@pytest.mark.parametrize("argv", [["bench", "--quick", "simulate"], ["regen", "--check"]])
def test_commands_that_read_the_checkout_refuse_without_one(argv, monkeypatch, tmp_path, capsys):
    """As installed from a wheel: no scenes/ or benchmarks/ beside the package -> exit 2, saying why."""
    import mechgen.bench.common
    import mechgen.regen

    monkeypatch.setattr(mechgen.bench.common, "ROOT", tmp_path)
    monkeypatch.setattr(mechgen.regen, "SCENES", tmp_path / "scenes")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "source checkout" in err and "scenes/" in err and "Traceback" not in err
