"""A parameter may be named E (Young's modulus; issue #14's friction beam names it so): it is a symbol of its
own, distinct from sympy's constant E = exp(1), in every backend, free or folded.

Reference: the rod m x'' + (E A / L) x = 0 has omega = sqrt(E A / (m L)); an output E_const * E with
E_const = exp(1) (math.e) checks that the two never merge."""
import math

import pytest

import mechgen

ROD = '''"""axial rod: m x'' + (E A / L) x = 0"""
import sympy as sp
from mechgen import Model, Param

model = Model("rod_e", doc=__doc__)
model.params(Param("m", 2.0, "kg"), Param("E", 3.0, "Pa"), Param("A", 1.0, "m^2"), Param("L", 1.0, "m"))
model.coordinates("x")
model.output("euler_times_E", lambda p: sp.E * p.E)


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.potential
def potential(q, p):
    return p.E * p.A / p.L / 2 * q.x**2
'''


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_parameter_E_is_not_eulers_number(tmp_path, backend):
    path = tmp_path / "rod.py"
    path.write_text(ROD)
    for values, free in (({}, None), ({"E": 5.0}, [])):
        system = mechgen.compile(str(path), values, free=free, backend=backend)
        E = values.get("E", 3.0)
        assert mechgen.modes(system).outputs["frequencies"] == pytest.approx([math.sqrt(E / 2.0)], rel=1e-13)
        assert system.outputs([0.0], [0.0])["euler_times_E"] == pytest.approx(math.e * E, rel=1e-15)


def test_scene_sets_E_by_expression(tmp_path):
    (tmp_path / "rod.py").write_text(ROD)
    (tmp_path / "rod.toml").write_text('title = "rod"\nmodel = "rod.py"\n[params]\nE = "2 * m + 1"\n'
                                       '[[analysis]]\nname = "m1"\nkind = "modes"\n')
    from mechgen.cli import main

    out = tmp_path / "out.json"
    assert main(["run", str(tmp_path / "rod.toml"), "--set", "m=3", "--json", str(out)]) == 0
    import json

    freq = json.loads(out.read_text())["analyses"][0]["outputs"]["frequencies"]
    assert freq == pytest.approx([math.sqrt(7.0 / 3.0)], rel=1e-13)
