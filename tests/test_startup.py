"""A shipped scene starts from the committed mechgen/generated/ layer: no sympy, the derived path's numbers.

Each run is a fresh subprocess with an empty MECHGEN_CACHE (so nothing comes from an earlier
derivation); a tiny runner reports the results, where the generated text came from, and which
of sympy, jinja2, scipy.optimize, mechgen.symbolic and the model module were imported by the end.
The reference is the same scene derived from scratch (the committed layer hidden).
"""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
RUNNER = """
import json, sys
from pathlib import Path
import mechgen.pipeline
if sys.argv[2] != "-":
    mechgen.pipeline.GENERATED = Path(sys.argv[2])
from mechgen.scene.run import run_scene
results = run_scene(sys.argv[1])
heavy = sorted({m for m in sys.modules if m.split(".")[0] in ("sympy", "jinja2")
                or m.startswith(("scipy.optimize", "mechgen.symbolic", "mechgen.models."))})
print(json.dumps({"origin": results["build"]["origin"], "heavy": heavy,
                  "analyses": [a["outputs"] for a in results["analyses"]]}, default=float))
"""


def _run(scene: str, cache: Path, generated: str = "-") -> dict:
    env = {**os.environ, "MECHGEN_CACHE": str(cache), "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", RUNNER, str(ROOT / "scenes" / scene), generated], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _numbers(value):
    """Every number of an output tree, flattened in order (strings compared as they are)."""
    if isinstance(value, dict):
        return [x for k in sorted(value) for x in _numbers(value[k])]
    if isinstance(value, (list, tuple)):
        return [x for v in value for x in _numbers(v)]
    return [value]


@pytest.mark.parametrize("scene", ["laval_rotor.toml", "beam_modes.toml"])
def test_shipped_scene_runs_from_the_committed_layer_without_sympy(scene, tmp_path):
    committed = _run(scene, tmp_path / "cache-a")
    assert committed["origin"] == "generated"
    assert committed["heavy"] == []
    derived = _run(scene, tmp_path / "cache-b", generated=str(tmp_path / "no-generated"))
    assert derived["origin"] == "derived"
    assert any(m.startswith("sympy") for m in derived["heavy"])  # the reference really derived
    a, b = _numbers(committed["analyses"]), _numbers(derived["analyses"])
    assert len(a) == len(b)
    for x, y in zip(a, b):
        if isinstance(x, (int, float)) and not isinstance(x, bool):
            np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12 * max(1.0, abs(x)))
        else:
            assert x == y


def test_a_small_stability_scene_starts_without_scipy(tmp_path):
    """Issue 30 (start): the Laval rotor's stability and Campbell sweep (8 states, conservative gyroscopic: numpy's
    Cholesky and eigvalsh) load neither scipy.linalg nor scipy.sparse (0.2-0.4 s of import, more than the scene
    needs to run); scipy's modules are imported at first use (mechgen.runtime.core.lazy_import)."""
    code = ("import json, sys\nfrom mechgen.scene.run import run_scene\nrun_scene(sys.argv[1])\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.startswith(('scipy.linalg', 'scipy.sparse')))))")
    env = {**os.environ, "MECHGEN_CACHE": str(tmp_path), "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", code, str(ROOT / "scenes" / "laval_rotor.toml")], env=env,
                         capture_output=True, text=True, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []
