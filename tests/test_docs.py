"""The user guide's Python API example (docs/guide.md, moved from the README) and the tutorial run verbatim.

Code blocks are taken from the Markdown as written: a block whose info string has
``file=PATH`` is written to PATH in a fresh folder; a ``python run`` block is run there
with this interpreter; a ``bash run`` block's ``mechgen ...`` lines are run as
``python -m mechgen ...``. Every block must exit 0; the blocks carry their own checks
against closed forms (the tutorial's bead on a string, the guide's pendulum).
"""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"^```(\w+)([^\n]*)\n(.*?)^```", re.S | re.M)


def blocks(text: str) -> list[tuple[str, dict, str]]:
    """(language, attributes, body) of every fenced block; attributes from ``key=value`` and bare words."""
    found = []
    for lang, info, body in BLOCK.findall(text):
        attrs = {}
        for word in info.split():
            key, _, value = word.partition("=")
            attrs[key] = value or True
        found.append((lang, attrs, body))
    return found


def section(text: str, heading: str) -> str:
    """The Markdown from ``heading`` to the next heading of the same level."""
    level = heading.split(" ")[0]
    start = text.index(heading + "\n")
    rest = text[start + len(heading):]
    end = re.search(rf"^{level} ", rest, re.M)
    return rest[: end.start()] if end else rest


def run_blocks(found, folder: Path) -> int:
    """Write the file blocks and run the run blocks in order; returns how many ran."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    env.setdefault("MPLBACKEND", "Agg")
    ran = 0
    for lang, attrs, body in found:
        if "file" in attrs:
            target = folder / attrs["file"]
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(body)
        if not attrs.get("run"):
            continue
        if lang == "python":
            commands = [[sys.executable, "-c", body]]
        elif lang == "bash":
            commands = [[sys.executable, "-m", *shlex.split(line)] for line in body.splitlines()
                        if line.startswith("mechgen ")]
        else:
            raise AssertionError(f"cannot run a {lang} block")
        for cmd in commands:
            proc = subprocess.run(cmd, cwd=folder, env=env, capture_output=True, text=True, timeout=600)
            assert proc.returncode == 0, f"{cmd[2:] if lang == 'bash' else body[:200]}\n{proc.stdout}\n{proc.stderr}"
            ran += 1
    return ran


def test_readme_python_api_runs_verbatim(tmp_path):
    found = blocks(section((ROOT / "docs" / "guide.md").read_text(), "## Python API"))
    assert run_blocks(found, tmp_path) >= 1


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lumped", "rotor", "hybrid", "rod"])
def test_tutorial_per_kind_of_model_runs_verbatim(name, tmp_path):
    """docs/tutorials/<name>.md: its file blocks written, its run blocks run in order; each run block asserts
    its numbers against closed forms (pendulums, Jeffcott whirl, restitution, the circular arc, beam theory) or
    stored ROSS frequencies."""
    found = blocks((ROOT / "docs" / "tutorials" / f"{name}.md").read_text())
    assert any("file" in a for _, a, _ in found)
    assert run_blocks(found, tmp_path) >= 2


@pytest.mark.slow
def test_tutorial_runs_verbatim(tmp_path):
    found = blocks((ROOT / "docs" / "tutorial.md").read_text())
    assert any("file" in a for _, a, _ in found)
    assert run_blocks(found, tmp_path) >= 2
