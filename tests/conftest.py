"""Shared fixtures: every test uses a private compile cache."""
import os

import pytest


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory):
    if "MECHGEN_CACHE" not in os.environ or os.environ.get("MECHGEN_TEST_SHARED_CACHE") != "1":
        os.environ["MECHGEN_CACHE"] = str(tmp_path_factory.mktemp("mechgen-cache"))
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
