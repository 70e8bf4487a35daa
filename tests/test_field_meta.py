"""FieldSystem's typed field facts (mechgen.runtime.fields.meta.FieldMeta) against the kernel meta dict they come from.

Reference: the ``"field"`` dict the lowering wrote (mechgen.codegen.lower_model.field_meta), still readable as
``system.info``: the typed view must say the same, with the documented defaults for the optional keys.
"""
from __future__ import annotations

import dataclasses

import pytest

import mechgen
from mechgen.runtime.fields.meta import FieldMeta


def test_defaults_of_the_optional_keys():
    meta = FieldMeta.of({"fields": ["w"], "jets": [["w", 0], ["w", 2]], "length": "L", "constraints": [["w", 0, "start"]]})
    assert meta.fields == ("w",) and meta.jets == (("w", 0), ("w", 2)) and meta.njets == 2
    assert meta.constraints == (("w", 0, "start"),) and meta.length == "L"
    assert (meta.points, meta.parts, meta.part_kinds, meta.shear_pairs) == ((), (), (), ())
    assert meta.constant_mass is False and meta.boundary_values is False
    with pytest.raises(dataclasses.FrozenInstanceError):
        meta.length = "H"  # type: ignore[misc]


def test_a_rotor_with_parts_says_what_its_kernel_meta_says():
    system = mechgen.compile("spinning_shaft", {"bc": "clamped-free", "discretisation": "timoshenko2", "N": 4},
                             backend="numpy")
    info, meta = system.info, system.field_meta
    assert meta == FieldMeta.of(info)
    assert list(meta.fields) == list(info["fields"])
    assert [list(j) for j in meta.jets] == [list(j) for j in info["jets"]]
    assert [list(c) for c in meta.constraints] == [list(c) for c in info["constraints"]]
    assert meta.length == info["length"] and system.value(meta.length) == system.value(info["length"])
    assert list(meta.points) == list(info.get("points", []))
    assert list(meta.part_kinds) == list(info.get("parts", {})) == ["bearing", "disk"]
    assert dict(meta.parts) == {k: tuple(v) for k, v in info["parts"].items()}
    assert [list(p) for p in meta.shear_pairs] == [list(p) for p in info["shear_pairs"]]
    assert meta.constant_mass is bool(info["constant_mass"])
    assert system.metadata.model == system.meta["model"] == "spinning_shaft"
