"""``mechgen regen``: write mechgen/generated/, the committed kernels the shipped scenes run.

For every shipped scene (``scenes/*.toml``) :func:`mechgen.scene.plan.plan_scene` gives the
compile requests that running it makes (its main system and one per structural choice that a
sweep visits), exactly as ``mechgen run`` plans them. For each request of a built-in model
this writes, under ``mechgen/generated/<model>/``:

* ``<key[:16]>.c`` - the generated source (readable; built once per machine into the user cache),
* ``<key[:16]>.c.json`` - the full request key, the request, the text's sha256 and the kernel specs,

and ``info.json`` (:mod:`mechgen.scene.info`) for every built-in model, and ``liegroup/``: the runtime's
numeric Lie-group maps (numpy and CasADi) generated from mechgen.symbolic.liegroup
(:mod:`mechgen.codegen.lower_liegroup`). The runtime loads these
when a request's key matches (mechgen.pipeline.generated_text), so a shipped scene starts without
deriving anything or importing sympy. Files that no request names are removed. Output is
byte-for-byte deterministic across processes and hash seeds.

``--check`` writes nothing. An entry is stale when a request has no committed entry (a model,
scene or mechgen source changed: the key covers them), a committed file is one no request names,
or the committed kernels differ from freshly generated ones structurally (kernel names, ports,
shapes, sparsity, sizes, operation counts) or numerically (each kernel evaluated at seeded random
inputs, to 1e-12 relative). Text is not compared: its formatting may change with the sympy version. The
``liegroup/`` modules are compared as text (byte for byte): an edit of the sympy source without a regen fails.
A passing check is remembered in the user cache for these sources and committed bytes, so a hook
that runs it again finds the answer at once.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

from mechgen import models
from mechgen.pipeline import GENERATED, committed_document, committed_paths, generate, read_committed

SCENES = Path(__file__).resolve().parent.parent / "scenes"
CHECK_FORMAT = "regen-check-1"
RTOL = 1e-12


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
    with os.fdopen(fd, "w", newline="\n", encoding="utf-8") as fh:
        fh.write(text)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)


def shipped_scenes(folder: Path = SCENES) -> list[Path]:
    """The shipped scene files, sorted."""
    return sorted(folder.glob("*.toml"))


def planned_requests(scenes=None) -> list[tuple]:
    """``(source, request)`` of every compile request the shipped scenes make (built-in models), deduplicated."""
    from mechgen.scene.info import lookup_model
    from mechgen.scene.load import load_scene
    from mechgen.scene.plan import plan_scene

    out, seen = [], set()
    for path in scenes if scenes is not None else shipped_scenes():
        scn = load_scene(str(path), lookup_model=lookup_model, model_names=models.names)
        plan = plan_scene(scn)
        if plan.source.origin != "built-in":
            continue
        for request in plan.requests():
            if request.key() not in seen:
                seen.add(request.key())
                out.append((plan.source, request))
    return sorted(out, key=lambda sr: (sr[1].model, sr[1].key()))


def fresh(source, request) -> dict:
    """{'text', 'specs'} of a request, derived now (never from a cache)."""
    from mechgen.scene.plan import derive_with

    from mechgen.errors import MechgenError

    model, spec = derive_with(source, request)()
    if spec.key() != request.spec_text():
        raise MechgenError(f"internal: the planned request of {request.model} ({request.spec_text()}) does not "
                           f"match the model's specialisation ({spec.key()})")
    return generate(model, spec, request.kernels, request.backend, request.cse)


def _info_documents() -> dict[Path, str]:
    """relative path -> text of every built-in model's info.json."""
    from mechgen.scene.info import info_document, info_key, info_of_model

    docs = {}
    for name in models.names():
        source = models.resolve(name)
        docs[Path(name) / "info.json"] = info_document(info_of_model(source.load()), info_key(source))
    return docs


def _liegroup_documents() -> dict[Path, str]:
    """relative path -> text of the generated Lie-group maps (mechgen/generated/liegroup/)."""
    from mechgen.codegen.lower_liegroup import generated_texts

    return {Path(rel): text for rel, text in generated_texts().items()}


def _existing(root: Path) -> set[Path]:
    """Committed files below the model folders, relative to root."""
    return {p.relative_to(root) for p in root.glob("*/*")
            if p.is_file() and not p.name.startswith(".") and "__pycache__" not in p.parts} | \
        {p.relative_to(root) for p in root.glob("*/__init__.py")}


def regen(*, check: bool = False, root: Path = GENERATED, scenes=None) -> list[str]:
    """Write (or with ``check`` verify) mechgen/generated/; returns the written / stale entries."""
    return check_generated(root, scenes) if check else write_generated(root, scenes)


def write_generated(root: Path = GENERATED, scenes=None) -> list[str]:
    """Write every planned request's text and JSON and every info.json, remove the rest; returns changed paths."""
    wanted: dict[Path, str] = {**_info_documents(), **_liegroup_documents()}
    for source, request in planned_requests(scenes):
        key = request.key()
        text_path, json_path = committed_paths(request.model, key, request.backend, Path("."))
        generated = fresh(source, request)
        wanted[text_path] = generated["text"]
        wanted[json_path] = committed_document(request, key, generated, text_path.name)
    changed = []
    for rel, text in sorted(wanted.items()):
        path = root / rel
        if not path.is_file() or path.read_bytes() != text.encode("utf-8"):
            _write(path, text)
            changed.append(str(rel))
    for rel in sorted(_existing(root) - set(wanted)):
        (root / rel).unlink()
        changed.append(f"{rel} (removed)")
    for folder in sorted(p for p in root.iterdir() if p.is_dir() and p.name != "__pycache__"):
        if not any(folder.iterdir()):
            folder.rmdir()
    return changed


def _stamp(root: Path, requests) -> str:
    """Key of a passing check: mechgen's sources, sympy's version, the planned keys and every committed byte."""
    from importlib.metadata import version

    from mechgen.codegen.cache import content_key, sources_digest

    files = sorted(_existing(root))
    return content_key(CHECK_FORMAT, sources_digest(), version("sympy"), *(r.key() for _, r in requests),
                       *(str(f).encode() + b"\n" + (root / f).read_bytes() for f in files))


def check_generated(root: Path = GENERATED, scenes=None) -> list[str]:
    """The stale entries of mechgen/generated/ (empty when it is current); writes nothing there."""
    from mechgen.codegen.cache import get_or_create, lookup
    from mechgen.scene.info import info_key

    requests = planned_requests(scenes)
    stamp = _stamp(root, requests)
    if lookup("regen-check", stamp) is not None:
        return []
    stale, named = [], set()
    for name in models.names():
        rel = Path(name) / "info.json"
        named.add(rel)
        try:
            current = json.loads((root / rel).read_text(encoding="utf-8")).get("key")
        except (OSError, ValueError):
            current = None
        if current != info_key(models.resolve(name)):
            stale.append(f"{rel} (missing or for another model file / mechgen version)")
    for source, request in requests:
        key = request.key()
        text_path, json_path = committed_paths(request.model, key, request.backend, Path("."))
        named |= {text_path, json_path}
        label = f"{text_path} ({request.model}: {request.spec_text()}; kernels {', '.join(request.kernels)})"
        committed = read_committed(request.model, key, request.backend, root)
        if committed is None:
            stale.append(f"{label}: missing")
            continue
        problem = compare_generated(committed, fresh(source, request), request.backend)
        if problem:
            stale.append(f"{label}: {problem}")
    for rel, text in _liegroup_documents().items():
        named.add(rel)
        path = root / rel
        if not path.is_file() or path.read_bytes() != text.encode("utf-8"):
            stale.append(f"{rel} (not the text that mechgen.codegen.lower_liegroup writes from "
                         "mechgen/symbolic/liegroup.py)")
    stale += [f"{rel} (no request names it)" for rel in sorted(_existing(root) - named)]
    if not stale:
        get_or_create("regen-check", stamp, lambda folder: (folder / "ok").write_text(stamp))
    return stale


def _structure(spec: dict) -> dict:
    """What the structural comparison covers of a kernel spec (no docs, no text)."""
    return {k: spec[k] for k in ("inputs", "outputs", "sizes", "slots", "ops", "signature", "meta")}


def compare_generated(committed: dict, fresh_: dict, backend: str) -> str | None:
    """Why two generations of one request differ (None when they agree structurally and numerically)."""
    a, b = committed["specs"], fresh_["specs"]
    if list(a) != list(b):
        return f"kernels {list(a)} != {list(b)}"
    for name in a:
        if _structure(a[name]) != _structure(b[name]):
            diff = [k for k in _structure(a[name]) if a[name].get(k) != b[name].get(k)]
            return f"kernel {name}: {', '.join(diff)} differ"
    if committed["text"] == fresh_["text"]:
        return None
    return numeric_difference(committed, fresh_, backend)


def _kernels(generated: dict, backend: str) -> dict:
    from mechgen.codegen.build import get_caller, load_shared
    from mechgen.runtime.core.kernels import c_kernels, load_module, numpy_kernels

    if backend == "c":
        return c_kernels(load_shared(generated["text"], stem="mgcheck"), generated["specs"], get_caller())
    with tempfile.TemporaryDirectory() as tmp:
        name = "mg_check_" + hashlib.sha256(generated["text"].encode()).hexdigest()[:16]
        path = Path(tmp) / f"{name}.py"
        path.write_text(generated["text"], encoding="utf-8")
        module = load_module(path, name)
    if backend == "numpy":
        return numpy_kernels(module)
    from mechgen.runtime.core.kernels import casadi_kernels

    return casadi_kernels(module, generated["specs"])


def numeric_difference(committed: dict, fresh_: dict, backend: str, *, sites: int = 4) -> str | None:
    """Evaluate both generations' kernels at the same seeded random inputs; a message when they differ.

    Real inputs are uniform in [0.5, 1.5] (seed 0 per kernel); every size is ``sites``. Kernels
    with integer inputs (a lattice's slot tables) are compared structurally only.
    """
    import numpy as np

    from mechgen.runtime.core.pattern import extent

    ka, kb = _kernels(committed, backend), _kernels(fresh_, backend)
    for name, spec in committed["specs"].items():
        if any(p["integer"] for p in spec["inputs"]):
            continue
        sizes = {n: sites for n in spec["sizes"]}
        rng = np.random.default_rng(0)
        inputs = {p["name"]: rng.uniform(0.5, 1.5, extent(p["extent"], sizes)) for p in spec["inputs"]}
        out_a = ka[name].evaluate(inputs, sizes, check=False)
        out_b = kb[name].evaluate(inputs, sizes, check=False)
        for port in out_a:
            x, y = np.asarray(out_a[port]), np.asarray(out_b[port])
            scale = max(1.0, float(np.nanmax(np.abs(x))) if x.size else 1.0)
            same_nan = np.array_equal(np.isnan(x), np.isnan(y))
            if not same_nan or not np.allclose(x, y, rtol=RTOL, atol=RTOL * scale, equal_nan=True):
                err = float(np.nanmax(np.abs(x - y))) if x.size else 0.0
                return f"kernel {name} output {port} differs by {err:.3g} at seeded random inputs"
    return None
