"""system.metadata, the typed view of a compiled system's kernel meta, against the meta dict it is read from
and the models' own declarations (names from the model files: mechgen/models/laval_rotor.py,
spring_pendulum.py, fpu_chain.py, euler_bernoulli_beam.py)."""
import dataclasses

import pytest

import mechgen
from mechgen.runtime.core.meta import SystemMeta


@pytest.mark.parametrize("name", ["spring_pendulum", "laval_rotor", "fpu_chain", "euler_bernoulli_beam"])
def test_metadata_reads_the_meta_dict(name):
    system = mechgen.compile(name)
    meta, typed = system.meta, system.metadata
    assert typed == SystemMeta.of(meta)
    assert typed.model == meta["model"] == name
    assert typed.params == tuple(meta.get("params", ()))
    assert typed.coordinates == tuple(meta["coordinates"])
    assert typed.internal == tuple(meta.get("internal", ()))
    assert typed.kind == meta.get("kind", "lumped")
    assert typed.reference == meta["source"]
    assert typed.is_lattice == system.is_lattice
    assert (typed.whirl is None) == (not meta.get("whirl"))
    with pytest.raises(dataclasses.FrozenInstanceError):
        typed.model = "other"


def test_metadata_of_known_models():
    rotor = mechgen.compile("laval_rotor").metadata
    assert rotor.whirl == ("x", "y", "theta_x", "theta_y") and rotor.kind == "lumped" and rotor.sites_param is None
    chain = mechgen.compile("fpu_chain").metadata
    assert chain.is_lattice and chain.sites_param and chain.ends
    pendulum = mechgen.compile("spring_pendulum").metadata
    assert pendulum.coordinates == ("r", "theta") and pendulum.whirl is None


def test_defaults_of_an_empty_meta():
    empty = SystemMeta.of({})
    assert empty == SystemMeta() and empty.reference is None and empty.kind == "lumped" and empty.params == ()
