"""Whitelist parser for the arithmetic expressions users write in scene files.

Scene values such as ``Omega = "2*pi*50"`` are parsed with ``ast.parse(text,
mode="eval")`` and the tree is checked node by node; nothing is ever passed to
``eval``, ``exec``, ``compile`` or ``sympify``. Accepted: int/float literals,
names, unary ``+``/``-``, binary ``+ - * / **``, parentheses, calls by plain
name of :data:`FUNCTIONS`, and the constants ``pi`` and ``e`` (constants always
win over values of the same name). Everything else raises
:class:`~mechgen.errors.InputError` naming the construct.

Resource limits: the text is at most :data:`MAX_LENGTH` characters, the tree at
most :data:`MAX_DEPTH` levels deep, and ``a ** b`` is evaluated in floating
point only when ``|b| <= MAX_EXPONENT`` and the result is finite, so inputs like
``9**9**9**9`` fail fast instead of building huge integers.
"""
from __future__ import annotations

import ast
import keyword
import math
import numbers
import re
from dataclasses import dataclass
from typing import Any, Callable, Mapping

from mechgen.errors import InputError

MAX_LENGTH = 1000
MAX_DEPTH = 200
MAX_EXPONENT = 1e4

CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

# name -> (function, minimum argument count, maximum argument count)
FUNCTIONS: dict[str, tuple[Callable[..., float], int, int]] = {
    "sin": (math.sin, 1, 1), "cos": (math.cos, 1, 1), "tan": (math.tan, 1, 1),
    "asin": (math.asin, 1, 1), "acos": (math.acos, 1, 1), "atan": (math.atan, 1, 1),
    "atan2": (math.atan2, 2, 2), "sinh": (math.sinh, 1, 1), "cosh": (math.cosh, 1, 1),
    "tanh": (math.tanh, 1, 1), "exp": (math.exp, 1, 1), "log": (math.log, 1, 2),
    "sqrt": (math.sqrt, 1, 1), "abs": (abs, 1, 1), "min": (min, 2, 16), "max": (max, 2, 16),
}

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")

_BINARY = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_UNARY = {ast.UAdd: "+", ast.USub: "-"}

_OTHER_OPS = {
    ast.Mod: "%", ast.FloorDiv: "//", ast.MatMult: "@", ast.BitAnd: "&", ast.BitOr: "|",
    ast.BitXor: "^", ast.LShift: "<<", ast.RShift: ">>", ast.Invert: "~", ast.Not: "not",
}

_CONSTRUCTS = {
    ast.Attribute: "attribute access", ast.Subscript: "subscript", ast.Lambda: "lambda",
    ast.Compare: "comparison", ast.BoolOp: "boolean operator", ast.IfExp: "conditional expression",
    ast.JoinedStr: "f-string", ast.FormattedValue: "f-string", ast.Starred: "starred argument",
    ast.List: "list", ast.Tuple: "tuple", ast.Set: "set", ast.Dict: "dict",
    ast.ListComp: "comprehension", ast.SetComp: "comprehension", ast.DictComp: "comprehension",
    ast.GeneratorExp: "generator expression", ast.NamedExpr: "assignment expression",
    ast.Await: "await", ast.Yield: "yield", ast.YieldFrom: "yield", ast.Slice: "slice",
}


def is_identifier(name: object) -> bool:
    """Whether ``name`` is safe to use as an identifier in generated code.

    Args:
        name: candidate name.

    Returns:
        True for ASCII names matching ``[A-Za-z_][A-Za-z0-9_]{0,63}`` that are
        not Python keywords and do not start with ``__``.
    """
    return (isinstance(name, str) and _IDENTIFIER.fullmatch(name) is not None
            and not keyword.iskeyword(name) and not name.startswith("__"))


def _show(text: str, limit: int = 60) -> str:
    """A short, single-line, quoted rendering of user text for messages."""
    shown = repr(text)
    return shown if len(shown) <= limit else shown[: limit - 4] + "...'"


@dataclass(frozen=True)
class Expression:
    """A validated arithmetic expression.

    Attributes:
        text: the source text.
        names: free names used (parameters), in order of first use; the
            constants ``pi`` and ``e`` and function names are not included.
        file: file the text came from, for error messages.
        key: dotted key the text came from, for error messages.
    """

    text: str
    names: tuple[str, ...]
    tree: tuple = ()
    file: str | None = None
    key: str | None = None

    def evaluate(self, values: Mapping[str, float]) -> float:
        """Evaluate with ``values`` bound to the free names.

        Args:
            values: name -> real number.

        Returns:
            The finite float value.

        Raises:
            InputError: unknown name, non-numeric value, domain error, overflow
                or a non-finite result.
        """
        missing = [n for n in self.names if n not in values]
        if missing:
            known = ", ".join(sorted(set(values) | set(CONSTANTS))) or "(none)"
            raise self._error(f"unknown name '{missing[0]}' in expression {_show(self.text)}",
                              f"one of the known names: {known}")
        result = _eval(self.tree, values, self)
        if not math.isfinite(result):
            raise self._error(f"expression {_show(self.text)} is not finite ({result})", "a finite value")
        return result

    def _error(self, message: str, expected: str | None = None) -> InputError:
        return InputError(message, file=self.file, key=self.key, expected=expected)


def parse_expression(text: str, *, file: str | None = None, key: str | None = None) -> Expression:
    """Parse and validate an expression string.

    Args:
        text: the expression, e.g. ``"2*pi*50"``.
        file: file the text came from (for messages).
        key: dotted key the text came from (for messages).

    Returns:
        The validated :class:`Expression`. Expressions without free names are
        evaluated once here, so their errors surface at parse time.

    Raises:
        InputError: the text is not a string, too long, not valid syntax, or
            uses a construct outside the whitelist.
    """
    expected = "an arithmetic expression of numbers, parameter names, pi, e, + - * / ** and " \
               "the functions " + ", ".join(FUNCTIONS)
    if not isinstance(text, str):
        raise InputError(f"expression must be a string, not {type(text).__name__}", file=file, key=key,
                         expected=expected)
    if len(text) > MAX_LENGTH:
        raise InputError(f"expression is {len(text)} characters long", file=file, key=key,
                         expected=f"at most {MAX_LENGTH} characters")
    if not text.strip():
        raise InputError("expression is empty", file=file, key=key, expected=expected)
    tree = _parse_tree(text, file, key, expected)
    names: list[str] = []
    shell = Expression(text, (), (), file, key)
    node = _convert(tree.body, names, shell, 0)
    expr = Expression(text, tuple(names), node, file, key)
    if not names:
        expr.evaluate({})
    return expr


def evaluate(text: str, values: Mapping[str, float], *, file: str | None = None,
             key: str | None = None) -> float:
    """Parse ``text`` and evaluate it with ``values``; see :func:`parse_expression`."""
    return parse_expression(text, file=file, key=key).evaluate(values)


def _parse_tree(text: str, file: str | None, key: str | None, expected: str) -> ast.Expression:
    """``ast.parse`` in eval mode, with every failure turned into InputError."""
    try:
        return ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        msg = exc.msg if isinstance(exc.msg, str) else "invalid syntax"
        raise InputError(f"expression {_show(text)} is not valid syntax ({msg})", file=file, key=key,
                         expected=expected) from None
    except (RecursionError, MemoryError, ValueError):
        raise InputError(f"expression {_show(text)} is too deeply nested", file=file, key=key,
                         expected=expected) from None


def _reject(node: ast.AST, what: str, expr: Expression) -> InputError:
    segment = ast.get_source_segment(expr.text.strip(), node) if hasattr(node, "lineno") else None
    where = f" ({_show(segment, 40)})" if segment else ""
    return expr._error(f"{what}{where} is not allowed in expression {_show(expr.text)}",
                       "only numbers, names, pi, e, + - * / **, parentheses and calls of "
                       + ", ".join(FUNCTIONS))


def _convert(node: ast.AST, names: list[str], expr: Expression, depth: int) -> tuple:
    """Check one AST node and turn it into a small tuple tree."""
    if depth > MAX_DEPTH:
        raise expr._error(f"expression {_show(expr.text)} is nested more than {MAX_DEPTH} levels deep",
                          f"at most {MAX_DEPTH} levels of nesting")
    if isinstance(node, ast.Constant):
        return ("num", _constant(node, expr))
    if isinstance(node, ast.Name):
        return _name(node, names, expr)
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return ("unary", _UNARY[type(node.op)], _convert(node.operand, names, expr, depth + 1))
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        return ("bin", _BINARY[type(node.op)], _convert(node.left, names, expr, depth + 1),
                _convert(node.right, names, expr, depth + 1))
    if isinstance(node, ast.Call):
        return _call(node, names, expr, depth)
    if isinstance(node, (ast.UnaryOp, ast.BinOp)):
        op = _OTHER_OPS.get(type(node.op), type(node.op).__name__)
        raise _reject(node, f"operator {op}", expr)
    raise _reject(node, _CONSTRUCTS.get(type(node), f"construct {type(node).__name__}"), expr)


def _constant(node: ast.Constant, expr: Expression) -> float:
    value = node.value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        what = "string literal" if isinstance(value, (str, bytes)) else f"{type(value).__name__} literal"
        raise _reject(node, what, expr)
    try:
        number = float(value)
    except OverflowError:
        raise _reject(node, "number too large", expr) from None
    if not math.isfinite(number):
        raise _reject(node, "non-finite number", expr)
    return number


def _name(node: ast.Name, names: list[str], expr: Expression) -> tuple:
    name = node.id
    if not is_identifier(name):
        raise _reject(node, f"name {_show(name)}", expr)
    if name in FUNCTIONS:
        raise _reject(node, f"function '{name}' used without a call", expr)
    if name in CONSTANTS:
        return ("num", CONSTANTS[name])
    if name not in names:
        names.append(name)
    return ("name", name)


def _call(node: ast.Call, names: list[str], expr: Expression, depth: int) -> tuple:
    if not isinstance(node.func, ast.Name):
        what = _CONSTRUCTS.get(type(node.func), "call of something other than a plain function name")
        raise _reject(node.func, what, expr)
    fname = node.func.id
    if fname not in FUNCTIONS:
        what = f"call of '{fname}'" if is_identifier(fname) else "call of a non-whitelisted name"
        raise _reject(node.func, what, expr)
    if node.keywords:
        raise _reject(node, "keyword argument", expr)
    for arg in node.args:
        if isinstance(arg, ast.Starred):
            raise _reject(arg, "starred argument", expr)
    _, low, high = FUNCTIONS[fname]
    if not low <= len(node.args) <= high:
        count = str(low) if low == high else f"{low} to {high}"
        raise expr._error(f"{fname}() takes {count} arguments, got {len(node.args)} in {_show(expr.text)}",
                          f"{count} arguments")
    args = tuple(_convert(a, names, expr, depth + 1) for a in node.args)
    return ("call", fname, args)


def _power(base: float, exponent: float, expr: Expression) -> float:
    if abs(exponent) > MAX_EXPONENT:
        raise expr._error(f"exponent {exponent:g} in {_show(expr.text)} is too large",
                          f"an exponent of magnitude at most {MAX_EXPONENT:g}")
    return math.pow(base, exponent)


def _binary(op: str, a: float, b: float, expr: Expression) -> float:
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        return a / b
    return _power(a, b, expr)


def _eval(node: tuple, values: Mapping[str, Any], expr: Expression) -> float:
    """Evaluate a tuple tree; every intermediate result must be finite."""
    tag = node[0]
    try:
        if tag == "num":
            result = node[1]
        elif tag == "name":
            result = _value(node[1], values, expr)
        elif tag == "unary":
            operand = _eval(node[2], values, expr)
            result = -operand if node[1] == "-" else operand
        elif tag == "bin":
            result = _binary(node[1], _eval(node[2], values, expr), _eval(node[3], values, expr), expr)
        else:
            result = float(FUNCTIONS[node[1]][0](*(_eval(a, values, expr) for a in node[2])))
    except ZeroDivisionError:
        raise expr._error(f"division by zero in expression {_show(expr.text)}", "a finite value") from None
    except (ValueError, OverflowError) as exc:
        raise expr._error(f"expression {_show(expr.text)} cannot be evaluated ({exc})",
                          "arguments inside each function's domain and a finite value") from None
    if not math.isfinite(result):
        raise expr._error(f"expression {_show(expr.text)} is not finite", "a finite value")
    return result


def _value(name: str, values: Mapping[str, Any], expr: Expression) -> float:
    value = values[name]
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise expr._error(f"name '{name}' in expression {_show(expr.text)} is not a number "
                          f"(value {_show(str(value))})", "names of numeric parameters")
    try:
        return float(value)
    except OverflowError:
        raise expr._error(f"value of '{name}' is too large", "a finite value") from None


# ------------------------------------------------------------------------------------------------ conditions

_COMPARE = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!="}
_TESTS: dict[str, Callable[[float, float], bool]] = {
    "<": lambda a, b: a < b, "<=": lambda a, b: a <= b, ">": lambda a, b: a > b, ">=": lambda a, b: a >= b,
    "==": lambda a, b: a == b, "!=": lambda a, b: a != b}
CONDITION = ("comparisons (< <= > >= == !=, chained as in 'a < b <= c') of arithmetic expressions, joined by "
             "'and' / 'or' with parentheses")


@dataclass(frozen=True)
class Condition:
    """A validated condition: comparisons of arithmetic expressions (:class:`Expression`, the same whitelist) joined
    by ``and`` / ``or``, e.g. ``"inner < outer or inner == 0 and outer == 0"``. A model declares such conditions on
    its part kinds (Model.part's ``checks``); nothing is evaluated as Python.

    Attributes:
        text: the source text.
        names: the free names used, in order of first use.
    """

    text: str
    names: tuple[str, ...]
    tree: tuple = ()

    def holds(self, values: Mapping[str, float]) -> bool:
        """Whether the condition holds with ``values`` bound to its names (InputError as Expression.evaluate)."""
        return _holds(self.tree, values)


def parse_condition(text: str, *, file: str | None = None, key: str | None = None) -> Condition:
    """Parse and validate a condition string (:class:`Condition`); InputError for anything outside its grammar."""
    if not isinstance(text, str) or not text.strip() or len(text) > MAX_LENGTH:
        raise InputError(f"condition is {_show(str(text))}", file=file, key=key,
                         expected=f"a non-empty string of at most {MAX_LENGTH} characters: {CONDITION}")
    stripped = text.strip()
    tree = _parse_tree(stripped, file, key, CONDITION)
    names: list[str] = []
    node = _condition(tree.body, stripped, names, file, key)
    return Condition(text, tuple(names), node)


def _condition(node: ast.AST, text: str, names: list[str], file: str | None, key: str | None) -> tuple:
    """A BoolOp of conditions, or a (chained) comparison whose operands are arithmetic expressions."""
    if isinstance(node, ast.BoolOp):
        tag = "and" if isinstance(node.op, ast.And) else "or"
        return (tag, tuple(_condition(v, text, names, file, key) for v in node.values))
    if isinstance(node, ast.Compare) and all(type(op) in _COMPARE for op in node.ops):
        sides = []
        for operand in (node.left, *node.comparators):
            expr = parse_expression(ast.get_source_segment(text, operand) or "", file=file, key=key)
            names.extend(n for n in expr.names if n not in names)
            sides.append(expr)
        return ("cmp", tuple(sides), tuple(_COMPARE[type(op)] for op in node.ops))
    segment = ast.get_source_segment(text, node) or text
    raise InputError(f"condition {_show(text)}: {_show(segment, 40)} is not a comparison", file=file, key=key,
                     expected=CONDITION)


def _holds(node: tuple, values: Mapping[str, float]) -> bool:
    if node[0] == "and":
        return all(_holds(child, values) for child in node[1])
    if node[0] == "or":
        return any(_holds(child, values) for child in node[1])
    numbers_ = [side.evaluate(values) for side in node[1]]
    return all(_TESTS[op](a, b) for op, a, b in zip(node[2], numbers_, numbers_[1:]))
