"""Shared fixtures: the test session uses a private compile cache (never the user's)."""
import os

import pytest


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory):
    """One fresh compile cache for the session, shared by pytest-xdist's workers (their common base folder), so
    that a model is built once per session rather than once per worker: the cache is built for concurrent
    processes (mechgen/codegen/cache.py: entries published by one rename, no lock files), and tests that
    damage or count a cache set their own MECHGEN_CACHE. MECHGEN_TEST_SHARED_CACHE=1 keeps the caller's."""
    if "MECHGEN_CACHE" not in os.environ or os.environ.get("MECHGEN_TEST_SHARED_CACHE") != "1":
        base = tmp_path_factory.getbasetemp()
        if os.environ.get("PYTEST_XDIST_WORKER"):
            base = base.parent  # the session's folder, shared by its workers (gw0, gw1 ... below it)
        cache = base / "mechgen-cache"
        cache.mkdir(exist_ok=True)
        os.environ["MECHGEN_CACHE"] = str(cache)
    yield


@pytest.fixture(scope="session")
def balloon_branches_run(tmp_path_factory):
    """``mechgen run scenes/balloon_branches.toml --json`` once per session (about 8 s): the outputs of each
    analysis by name, as read back from the JSON file. Shared by tests/test_balloon.py (the single-loop branch
    and p_e,min) and tests/test_balloon_loops.py (the multi-loop families), which read different parts of the
    same run; the tests only read it."""
    import json
    from pathlib import Path

    from mechgen.cli import main

    target = tmp_path_factory.mktemp("balloon_branches") / "branches.json"
    scene = Path(__file__).resolve().parents[1] / "scenes" / "balloon_branches.toml"
    assert main(["run", str(scene), "--json", str(target)]) == 0
    return {a["name"]: a["outputs"] for a in json.loads(target.read_text())["analyses"]}
