"""Non-finite and named constants in generated kernels, and laws singular at a folded value (issue 12, section 5).

A parameter of 1e200 folded into a kernel makes 1e200**2 = 1e400, a finite sympy Float whose double
is infinity; the printers wrote ``inf``, a name the numpy and CasADi modules do not define. Now each
backend writes its own infinity, so the kernel computes what IEEE arithmetic gives: references are
the same expressions in 60-digit mpmath rounded to a double (atan(1e400 x) = pi/2 - 1e-400/x to a
double is pi/2; 1/(1 + 1e400 x^2) underflows to 0). A law that is singular at a folded value
(W = p/beta at beta = 0: sympy's zoo) is refused at specialisation naming the parameter and its value.
"""
from __future__ import annotations

import shutil

import mpmath
import numpy as np
import pytest
import sympy as sp

import mechgen
from mechgen.cli import main
from mechgen.codegen.ir import Write
from mechgen.codegen.lower import canonical_block
from mechgen.codegen.printing import c_code, casadi_code, numpy_code
from mechgen.errors import ModelError
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

CC = shutil.which("cc") or shutil.which("gcc")
BACKENDS = ["numpy", "casadi", "c"]
X = 0.5


def _needs(backend):
    if backend == "casadi":
        pytest.importorskip("casadi")
    if backend == "c" and CC is None:
        pytest.skip("no C compiler")


def _overflowing() -> Model:
    """Outputs whose folded constants overflow a double: k**2 with k = 1e200, n**24 with n = 2**52 (an exact
    integer of 1249 bits), and the named constants E and EulerGamma."""
    model = Model("overflowing")
    model.params(Param("k", 1e200), Param("n", 2.0**52), Param("m", 1.0))
    model.coordinates("x")
    model.kinetic(lambda v, p: p.m * v.x**2 / 2)
    model.potential(lambda q: q.x**2 / 2)
    model.output("angle", lambda q, p: sp.atan(p.k**2 * q.x))
    model.output("small", lambda q, p: 1 / (1 + p.k**2 * q.x**2))
    model.output("angle_n", lambda q, p: sp.atan(-p.n**24 * q.x))
    model.output("named", lambda q: sp.E * q.x + sp.EulerGamma)
    return model


def _reference() -> dict:
    mpmath.mp.dps = 60
    k2, n24, x = mpmath.mpf(10) ** 400, mpmath.mpf(2) ** (52 * 24), mpmath.mpf(X)
    return {"angle": float(mpmath.atan(k2 * x)), "small": float(1 / (1 + k2 * x**2)),
            "angle_n": float(mpmath.atan(-n24 * x)), "named": float(mpmath.e * x + mpmath.euler)}


@pytest.mark.parametrize("backend", BACKENDS)
def test_overflowing_folded_constants_build_and_evaluate_as_ieee_doubles(backend):
    _needs(backend)
    system = mechgen.compile(_overflowing(), free=("m",), backend=backend, kernels=("outputs",))
    got = system.outputs(np.array([X]), np.array([0.0]))
    ref = _reference()
    assert ref["angle"] == np.pi / 2 and ref["small"] == 0.0 and ref["angle_n"] == -np.pi / 2
    for name, value in ref.items():
        assert got[name] == pytest.approx(value, rel=1e-15, abs=0.0), name


@pytest.mark.parametrize("printer, inf, nan", [(c_code, "INFINITY", "NAN"), (numpy_code, "np.inf", "np.nan"),
                                               (casadi_code, "np.inf", "np.nan")])
def test_printers_name_the_backends_infinity_and_nan(printer, inf, nan):
    g = sp.Symbol("g0", real=True)
    assert printer(g * sp.Float(1e200) ** 2) == f"{inf}*g0"
    assert printer(g - sp.Float(1e200) ** 2) == f"g0 + (-{inf})"
    assert printer(sp.Integer(10) ** 400 * g) == f"{inf}*g0"
    assert printer(sp.oo * g) == f"{inf}*g0"
    assert printer(sp.nan) == nan
    for bad in (sp.zoo * g, g + sp.I):
        with pytest.raises(ValueError):
            printer(bad)


def test_numpy_text_of_overflowing_constants_evaluates():
    g = sp.Symbol("g0", real=True)
    text = numpy_code(sp.atan(sp.Float(1e200) ** 2 * g) + sp.E)
    assert eval(text, {"np": np}, {"g0": X}) == np.pi / 2 + float(mpmath.e)


# ----------------------------------------------------------------------------- singular laws


def _law(potential, **params) -> Model:
    model = Model("singular_law")
    model.params(*[Param(name, value) for name, value in params.items()])
    model.coordinates("x")
    model.kinetic(lambda v: v.x**2 / 2)
    model.potential(potential)
    return model


SINGULAR = {
    # name: (potential, parameter values, the parameter to name, its value as written, what the result held)
    "division_by_zero": (lambda q, p: q.x**2 / (2 * p.c), {"c": 0.0}, "c", "0.0", "zoo"),
    "zero_over_zero": (lambda q, p: p.a / p.b * q.x**2, {"a": 0.0, "b": 0.0}, "b", "0.0", "nan"),
    "log_of_zero": (lambda q, p: sp.log(p.c) * q.x**2, {"c": 0.0}, "c", "0.0", "zoo"),
    "root_of_negative": (lambda q, p: sp.sqrt(p.c) * q.x**2, {"c": -1.0}, "c", "-1.0", "imaginary"),
    "negative_power_of_zero": (lambda q, p: p.c ** -0.5 * q.x**2, {"c": 0.0}, "c", "0.0", "zoo"),
}


@pytest.mark.parametrize("case", sorted(SINGULAR))
def test_a_law_singular_at_a_folded_value_is_refused_naming_the_parameter(case):
    potential, values, name, text, held = SINGULAR[case]
    with pytest.raises(ModelError) as info:
        mechgen.compile(_law(potential, **{k: 1.0 for k in values}), values, free=(), backend="numpy")
    err = info.value
    assert err.key == f"params.{name}" and f"{name} = {text}" in str(err) and held in str(err), str(err)
    assert err.file == __file__ and "line " in str(err)  # the line of the declared function


def test_the_same_law_at_a_regular_value_or_kept_free_builds():
    """V = x^2 / (2 c): K = 1/c (at c = 0.25 folded: 4; free, a kernel input: the same)."""
    law = SINGULAR["division_by_zero"][0]
    for free in ((), ("c",)):
        system = mechgen.compile(_law(law, c=0.25), free=free, backend="numpy")
        assert system.linear(np.zeros(1))["K"][0, 0] == 4.0


def test_balloon_string_at_beta_zero_is_refused_at_params_beta():
    """The complementary energy of the string laws is C = n^2 / (2 beta) + ...: singular at beta = 0."""
    from mechgen.pipeline import generate
    from mechgen.symbolic.specialize import specialize

    model = mechgen.load_model("balloon_string")
    with pytest.raises(ModelError) as info:
        generate(model, specialize(model, {"beta": 0.0}), ["hbvp_rates"], "numpy")
    assert info.value.key == "params.beta" and "beta = 0.0" in str(info.value)
    assert info.value.file.endswith("balloon_string.py")


def test_lowering_refuses_non_finite_derived_expressions():
    """The second line of defence: an expression that reached lowering with zoo in it."""
    g = sp.Symbol("x", real=True)
    with pytest.raises(ModelError) as info:
        canonical_block([(g, "q", 0, False)], [Write("r", 0, sp.zoo * g)], model="m")
    assert "singular" in str(info.value) and "zoo" in str(info.value)


def test_a_singular_law_in_a_scene_exits_2_naming_the_file_and_parameter(tmp_path, capsys):
    path = tmp_path / "law.py"
    path.write_text("from mechgen import Model, Param\nmodel = Model('law')\nmodel.params(Param('c', 1.0))\n"
                    "model.coordinates('x')\nmodel.kinetic(lambda v: v.x**2 / 2)\n"
                    "model.potential(lambda q, p: q.x**2 / (2 * p.c))\n")
    scene = tmp_path / "scene.toml"
    scene.write_text('model = "law.py"\nbackend = "numpy"\n[params]\nc = 0.0\n'
                     '[[analysis]]\nname = "m"\nkind = "modes"\n')
    code = main(["run", str(scene), "--json", str(tmp_path / "never.json")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert str(path) in err and "params.c" in err and "c = 0.0" in err, err
    assert not (tmp_path / "never.json").exists()
