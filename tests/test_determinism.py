"""Deterministic generation, and the committed mechgen/generated is what the shipped scenes run.

* `mechgen regen` writes the same bytes in separate processes with different hash seeds;
* `mechgen regen --check` passes on the committed layer and finds a changed kernel (numerically)
  while accepting a reformatted one (text is not compared).
"""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from mechgen.pipeline import GENERATED

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = """
import hashlib, sys
from pathlib import Path
from mechgen.regen import write_generated
root = Path(sys.argv[1])
write_generated(root, [Path(p) for p in sys.argv[2:]])
h = hashlib.sha256()
for p in sorted(root.rglob('*')):
    if p.is_file():
        h.update(str(p.relative_to(root)).encode()); h.update(p.read_bytes())
print(h.hexdigest())
"""
SCENES = [ROOT / "scenes" / "laval_rotor.toml", ROOT / "scenes" / "beam_modes.toml"]
#: every shipped scene of the laval_rotor model (each makes its own compile request, its own committed file)
LAVAL_SCENES = sorted(p for p in (ROOT / "scenes").glob("*.toml") if 'model = "laval_rotor"' in p.read_text())


def _digest(seed: str, root: Path) -> str:
    env = dict(os.environ, PYTHONHASHSEED=seed)
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(root), *map(str, SCENES)], env=env,
                         capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_generation_is_byte_identical_across_processes(tmp_path):
    first, second = _digest("1", tmp_path / "a"), _digest("12345", tmp_path / "b")
    assert first == second
    # and equal to the committed files for the same requests
    for path in (tmp_path / "a").rglob("*.c"):
        assert path.read_bytes() == (GENERATED / path.relative_to(tmp_path / "a")).read_bytes()


@pytest.mark.slow
def test_committed_generated_code_is_current():
    from mechgen.regen import regen

    assert regen(check=True) == []


def _copy_laval(tmp_path) -> tuple[Path, Path]:
    root = tmp_path / "generated"
    shutil.copytree(GENERATED, root)
    text = sorted((root / "laval_rotor").glob("*.c"))[0]  # one of the shipped scenes' laval_rotor requests
    return root, text


def _rehash(text: Path) -> None:
    """Keep the committed JSON consistent with an edited text (as a regenerated one would be)."""
    import hashlib

    doc_path = text.with_name(text.name + ".json")
    doc = json.loads(doc_path.read_text())
    doc["sha256"] = hashlib.sha256(text.read_bytes()).hexdigest()
    doc_path.write_text(json.dumps(doc, indent=1) + "\n")


def test_check_finds_a_numerically_different_kernel(tmp_path):
    from mechgen.regen import check_generated

    root, text = _copy_laval(tmp_path)
    source = text.read_text()
    import re

    # an output entry that is a constant (out0[0] = 10.0, the rotor's mass): same structure, another number
    m = re.search(r"(out\d+\[\d+\] = )(\d+\.\d+);", source)
    assert m, "the laval kernel stores a constant entry"
    changed = source[:m.start(2)] + repr(float(m.group(2)) * 1.5 + 1.0) + source[m.end(2):]
    assert changed != source
    text.write_text(changed)
    _rehash(text)
    stale = [s for s in check_generated(root, LAVAL_SCENES) if s.startswith("laval_rotor/")]
    assert len(stale) == 1 and "differs" in stale[0] and text.name in stale[0]


def test_check_accepts_a_reformatted_kernel_and_flags_unused_files(tmp_path):
    from mechgen.regen import check_generated

    root, text = _copy_laval(tmp_path)
    text.write_text("/* reformatted */\n" + text.read_text().replace(";\n", ";\n\n"))
    _rehash(text)
    (root / "laval_rotor" / "kernels.c").write_text("/* left over */\n")
    stale = [s for s in check_generated(root, LAVAL_SCENES) if s.startswith("laval_rotor/")]
    assert stale == ["laval_rotor/kernels.c (no request names it)"]
