"""The numpy backend's one-point path (issue 32 item 2): a kernel without loops evaluates one point on Python
floats (module ``math``) instead of a numpy call per operation on 1-element arrays.

References: the same kernel's vectorised body (two identical rows, which never take the point path), sympy's own
value of printed expressions, and the C backend of the same model.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import mechgen
from mechgen.codegen.printing import MathPrinter
from mechgen.symbolic.powers import abs_power, signed_power

x, y = sp.symbols("x y", real=True)
CASES = [sp.sin(x) * sp.cos(y) / (1 + x**2) ** 2, sp.sqrt(x**2 + y**2), sp.atan2(y, x), sp.exp(-x) * sp.tanh(y),
         sp.Abs(x - y) ** sp.Rational(3, 2), sp.sign(x - 0.3), sp.Max(x, y) - sp.Min(x, y),
         sp.Piecewise((x**2, x < 0.5), (y, True)), signed_power(x - 1, sp.Rational(3, 2)),
         abs_power(y - 1, sp.Rational(5, 2)), (x + y) ** -3, x ** 2.5]


@pytest.mark.parametrize("expr", CASES, ids=str)
def test_math_printer_evaluates_to_sympys_value(expr):
    values = {x: 0.7, y: 0.3}
    text = MathPrinter().doprint(expr)
    assert eval(text, {"math": math}, {"x": 0.7, "y": 0.3}) == pytest.approx(float(expr.subs(values)), rel=1e-14)


def test_a_domain_error_raises_on_floats():
    """math raises where numpy gives nan: the kernel then runs its numpy body (test below)."""
    with pytest.raises(ValueError):
        eval(MathPrinter().doprint(sp.sqrt(x)), {"math": math}, {"x": -1.0})
    with pytest.raises(ValueError):
        eval(MathPrinter().doprint(x ** 2.5), {"math": math}, {"x": -1.0})


def point_inputs(system, kernel, rng) -> dict:
    """A random point (0.3 .. 0.7 in every batched entry), the system's parameters, t = 0.3."""
    inputs = {}
    for port in kernel.spec["inputs"]:
        if port["name"] == "p":
            inputs["p"] = system.params
        elif port["batched"]:
            inputs[port["name"]] = 0.3 + 0.4 * rng.random((1, port["extent"]["const"]))
        else:
            inputs[port["name"]] = np.full(port["extent"]["const"], 0.3)
    return inputs


@pytest.mark.parametrize("model", ["spring_pendulum", "laval_rotor", "duffing", "rate_state_inertial",
                                   "pendulum_9_by_ad"])
def test_point_path_equals_the_vectorised_body_and_c(model):
    """Every kernel of the model at a random point: the point path (one row), the numpy body (two equal rows) and
    the C kernel agree to round-off (1e-12 of the output's scale). The 9-link pendulum is derived by AD: its
    kernels are program blocks, printed in each dialect by mechgen.codegen.program_text."""
    if model == "pendulum_9_by_ad":
        from mechgen.bench.multibody import pendulum_model

        model = pendulum_model(9)
    numpy_sys, c_sys = mechgen.compile(model, backend="numpy"), mechgen.compile(model, backend="c")
    rng = np.random.default_rng(7)
    checked = 0
    for name, kernel in numpy_sys.kernels.items():
        if kernel.spec.get("sizes") or any(p["integer"] for p in kernel.spec["inputs"]):
            continue
        inputs = point_inputs(numpy_sys, kernel, rng)
        one = kernel.evaluate(inputs, check=False)
        two = kernel.evaluate({k: (np.vstack([v, v]) if v.ndim == 2 else v) for k, v in inputs.items()},
                              check=False)
        compiled = c_sys.kernels[name].evaluate(inputs, check=False)
        for out, value in one.items():
            scale = max(1.0, float(np.max(np.abs(value)))) if value.size else 1.0
            assert np.allclose(value, two[out][:1], rtol=0, atol=1e-12 * scale), (name, out)
            assert np.allclose(value, compiled[out], rtol=0, atol=1e-12 * scale), (name, out)
        checked += 1
    assert checked >= 3


def test_domain_error_falls_back_to_numpy_values():
    """A law with sqrt of a coordinate at a negative value: the one-point call gives numpy's nan (which the
    runtime's NaN check then names), not a Python exception."""
    from mechgen import Model, Param

    model = Model("sqrt_spring")
    model.params(Param("k", 1.0, "N/m", "stiffness"))
    model.coordinates("x")
    model.kinetic(lambda v: v.x**2 / 2)
    model.potential(lambda q, p: p.k * sp.sqrt(q.x) ** 3)
    system = mechgen.compile(model, backend="numpy")
    kernel = system.kernels["residual"]
    inputs = point_inputs(system, kernel, np.random.default_rng(1))
    inputs["q"] = np.array([[-1.0]])
    with np.errstate(invalid="ignore"):
        out = kernel.evaluate(inputs, check=False)
    assert np.isnan(np.concatenate([v.ravel() for v in out.values()])).any()
    inputs["q"] = np.array([[0.25]])
    out = kernel.evaluate(inputs, check=False)
    assert np.allclose(np.concatenate([v.ravel() for v in out.values()]),
                       np.concatenate([v.ravel() for v in system_c_residual(model, inputs).values()]), atol=1e-14)


def system_c_residual(model, inputs) -> dict:
    return mechgen.compile(model, backend="c").kernels["residual"].evaluate(inputs, check=False)
