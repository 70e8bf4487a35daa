"""Shared fixtures: every test uses a private compile cache."""
import os

import pytest


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory):
    if "MECHGEN_CACHE" not in os.environ or os.environ.get("MECHGEN_TEST_SHARED_CACHE") != "1":
        os.environ["MECHGEN_CACHE"] = str(tmp_path_factory.mktemp("mechgen-cache"))
    yield
