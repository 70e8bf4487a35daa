"""Printed expressions evaluate to sympy's values (regression: a / b**2 once printed as a/b*b)."""
import numpy as np
import pytest
import sympy as sp

from mechgen.codegen.printing import CPrinter, NumpyPrinter

x, y, a = sp.symbols("x y a", real=True)
CASES = [a * (x**2 + y**2) ** -2, a * x**3 / (x + 1) * (x**2 + y**2) ** -2, a / (x * y) ** 2,
         a**2 / (x**2 + 1), (x + y) ** 3 / (a - x) ** 4, x ** -1 * (y + 1) ** -3, a / x**2 / y**2]


@pytest.mark.parametrize("expr", CASES, ids=str)
def test_numpy_printer_keeps_denominators_whole(expr):
    values = {"x": 0.7, "y": 0.3, "a": 1.3}
    text = NumpyPrinter().doprint(expr)
    assert eval(text, {"np": np}, dict(values)) == pytest.approx(float(expr.subs({x: 0.7, y: 0.3, a: 1.3})),
                                                                 rel=1e-14)


@pytest.mark.parametrize("expr", CASES, ids=str)
def test_c_printer_brackets_unrolled_powers(expr):
    """C and Python share the operator precedences used here, so the C text evaluates alike in Python."""
    text = CPrinter().doprint(expr).replace("sqrt", "np.sqrt")
    value = eval(text, {"np": np}, {"x": 0.7, "y": 0.3, "a": 1.3})
    assert value == pytest.approx(float(expr.subs({x: 0.7, y: 0.3, a: 1.3})), rel=1e-14)
