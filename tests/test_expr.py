"""The whitelist expression parser: values, hostile inputs, resource limits, names."""
import math

import pytest

from mechgen.errors import InputError
from mechgen.scene.expr import Expression, evaluate, is_identifier, parse_expression

VALUES = {"x": 0.3, "y": -1.7, "Omega": 12.5, "n": 3}

CASES = [
    ("1", 1.0),
    ("-2.5e-3", -2.5e-3),
    ("+x", 0.3),
    ("2*pi*50", 2 * math.pi * 50),
    ("e**2", math.e ** 2),
    ("(1 + 2) * 3 - 4 / 8", 8.5),
    ("2**-1", 0.5),
    ("2**3**2", 2.0 ** 9),
    ("-x**2", -(0.3 ** 2)),
    ("x**n", 0.3 ** 3),
    ("sin(x) + cos(y) * tan(x)", math.sin(0.3) + math.cos(-1.7) * math.tan(0.3)),
    ("asin(x) + acos(x) + atan(y)", math.asin(0.3) + math.acos(0.3) + math.atan(-1.7)),
    ("atan2(y, x)", math.atan2(-1.7, 0.3)),
    ("sinh(x) - cosh(x) + tanh(y)", math.sinh(0.3) - math.cosh(0.3) + math.tanh(-1.7)),
    ("exp(x) * log(Omega)", math.exp(0.3) * math.log(12.5)),
    ("log(8, 2)", 3.0),
    ("sqrt(Omega) + abs(y)", math.sqrt(12.5) + 1.7),
    ("min(x, y, 0) + max(x, y)", -1.7 + 0.3),
    ("((((x))))", 0.3),
]


@pytest.mark.parametrize("text, expected", CASES)
def test_values_match_math(text, expected):
    assert evaluate(text, VALUES) == pytest.approx(expected, rel=1e-14, abs=1e-15)


def test_expression_object_is_frozen_and_reports_names():
    expr = parse_expression("a*sin(b) + a + pi + e", key="params.c")
    assert isinstance(expr, Expression)
    assert expr.names == ("a", "b")
    assert expr.evaluate({"a": 2.0, "b": 0.0}) == pytest.approx(2.0 + math.pi + math.e)
    with pytest.raises(AttributeError):
        expr.text = "1"  # type: ignore[misc]


HOSTILE = [
    ("__import__('os')", "call"),
    ("__import__('os').system('echo pwned')", "attribute"),
    ("().__class__", "attribute"),
    ("().__class__.__bases__[0].__subclasses__()", "attribute"),
    ("(lambda: 1)()", "lambda"),
    ("sin(1)(2)", "call of something other"),
    ("open('x')", "open"),
    ("lambda: 1", "lambda"),
    ("x.y", "attribute"),
    ("a[0]", "subscript"),
    ("1 if 1 else 2", "conditional"),
    ("'abc'", "string"),
    ("b'abc'", "string"),
    ("f'{x}'", "f-string"),
    ("x < 1", "comparison"),
    ("x and y", "boolean"),
    ("not x", "not"),
    ("x % 2", "%"),
    ("x // 2", "//"),
    ("x @ y", "@"),
    ("~1", "~"),
    ("True", "bool"),
    ("None", "NoneType"),
    ("1j", "complex"),
    ("[1, 2]", "list"),
    ("(1, 2)", "tuple"),
    ("{1: 2}", "dict"),
    ("[i for i in x]", "comprehension"),
    ("(y := 1)", "assignment"),
    ("sin(x=1)", "keyword"),
    ("max(*x)", "starred"),
    ("sin", "without a call"),
    ("foo(1)", "call of 'foo'"),
    ("__x + 1", "name"),
    ("π * 2", "name"),
    ("1e400", "non-finite"),
    ("x; import os", "syntax"),
    ("import os", "syntax"),
    ("", "empty"),
    ("sin(1, 2)", "arguments"),
    ("atan2(1)", "arguments"),
]


@pytest.mark.parametrize("text, word", HOSTILE)
def test_hostile_inputs_are_rejected(text, word):
    with pytest.raises(InputError) as info:
        evaluate(text, VALUES, file="s.toml", key="params.x")
    message = str(info.value)
    assert word in message
    assert "s.toml" in message and "params.x" in message
    assert "\n" not in message


@pytest.mark.parametrize("text", ["9**9**9**9", "9.0**99999", "10**400", "2**(10**5)", "exp(1000)", "1e308*10",
                                  "(-8)**(1/3)", "1/0", "sqrt(-1)", "log(0)"])
def test_resource_and_domain_errors(text):
    with pytest.raises(InputError):
        evaluate(text, {})


def test_huge_power_fails_at_parse_time_and_fast():
    with pytest.raises(InputError, match="exponent"):
        parse_expression("9**9**9**9")


def test_huge_power_with_names_fails_at_evaluate():
    expr = parse_expression("x**y")
    with pytest.raises(InputError, match="exponent"):
        expr.evaluate({"x": 9.0, "y": 1e6})


@pytest.mark.parametrize("text", ["1+" * 600 + "1", "-" * 999 + "1", "x" * 1001, "(" * 300 + "1" + ")" * 300])
def test_long_or_deep_text_is_rejected(text):
    with pytest.raises(InputError):
        evaluate(text, {"x" * 1001: 1.0})


def test_non_string_input_is_rejected():
    with pytest.raises(InputError):
        parse_expression(3.0)  # type: ignore[arg-type]


def test_unknown_name_lists_known_names():
    with pytest.raises(InputError) as info:
        evaluate("Omega * r", {"Omega": 1.0, "m": 2.0}, file="s.toml", key="analysis[1].t_end")
    message = str(info.value)
    assert "'r'" in message
    assert "Omega" in message and "m" in message and "pi" in message


def test_non_numeric_value_is_rejected():
    with pytest.raises(InputError, match="not a number"):
        evaluate("law * 2", {"law": "neo_hookean"})


def test_constants_are_not_free_names():
    assert parse_expression("pi*e").names == ()


@pytest.mark.parametrize("name, ok", [
    ("x", True), ("Omega_2", True), ("_a", True), ("a" * 64, True), ("a" * 65, False), ("2x", False),
    ("__x", False), ("class", False), ("x\n", False), ("x y", False), ("x-y", False), ("é", False), ("", False),
    ('x); import os; os.system("echo pwned")  #', False), (3, False),
])
def test_is_identifier(name, ok):
    assert is_identifier(name) is ok
