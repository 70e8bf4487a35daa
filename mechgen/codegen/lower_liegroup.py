"""The runtime's numeric so(3)/se(3) maps, generated from their sympy source (mechgen.symbolic.liegroup).

The rods' numerics (mechgen.runtime.rods) need the Lie-group maps batched in numpy and as CasADi SX for their
AD Jacobians; the runtime never imports sympy, so their text is generated here and committed under
``mechgen/generated/liegroup/`` by ``mechgen regen`` (checked by ``mechgen regen --check``). What comes from the
sympy module, and nothing else:

* each map's entries (exp_so3, jac_left_so3, jac_left_so3_inv, q_block, exp_se3, jac_left_se3, jac_right_se3),
  common subexpressions eliminated, with every angle function a of the squared angle s = w.w kept as a call
  ``angle("a1", s)`` of the caller's evaluator (``mechgen.symbolic.liegroup``'s SafeFunctions, opaque);
* each angle function's Taylor coefficients in powers of s (``COEFFS``), the bound of the series interval
  (``SERIES_BELOW``, in s) and its closed form in the angle t = sqrt(s) (``closed_<name>(t)``).

How the series and the closed form are chosen per point (numpy: the batch's largest angle sets the number of
terms; CasADi: an if_else) is the runtime's glue (runtime/rods/liegroup.py, runtime/rods/ad.py). Output is
deterministic: sympy's CSE over entries in row-major order, numbers printed with 17 digits.
"""
from __future__ import annotations

import sympy as sp

from mechgen.codegen.printing import CasadiPrinter, CPrinter, NumpyPrinter
from mechgen.symbolic import liegroup as lg
from mechgen.symbolic.safe import SafeFunctionBase

#: the angle functions, by their short name (the SafeFunction's name without ``angle_``)
ANGLES = {"sinc": lg.sinc_sq, "a1": lg.a1_sq, "a2": lg.a2_sq, "a3": lg.a3_sq, "a4": lg.a4_sq, "b": lg.b_sq}

_W, _V = sp.symbols("w0:3", real=True), sp.symbols("v0:3", real=True)
_XI = sp.symbols("xi0:6", real=True)
_T = sp.Symbol("t", positive=True)

#: name, the map's inputs (name, symbols), its sympy expression, its docstring's formula
MAPS = (
    ("exp_so3", (("w", _W),), lambda: lg.exp_so3(_W), "exp(hat3 w) = I + sinc W + a1 W^2"),
    ("jac_left_so3", (("w", _W),), lambda: lg.jac_left_so3(_W), "J_l(w) = I + a1 W + a2 W^2"),
    ("jac_left_so3_inv", (("w", _W),), lambda: lg.jac_left_so3_inv(_W), "J_l(w)^-1 = I - W/2 + b W^2"),
    ("q_block", (("v", _V), ("w", _W)), lambda: lg.q_block(_V, _W),
     "Q(v, w), the upper-right block of the SE(3) left Jacobian (Barfoot & Furgale 2014, eq. (102))"),
    ("exp_se3", (("xi", _XI),), lambda: lg.exp_se3(_XI), "exp(hat6(v, w)) = [[exp_so3 w, J_l(w) v], [0, 1]]"),
    ("jac_left_se3", (("xi", _XI),), lambda: lg.jac_left_se3(_XI), "J_l(xi) = [[J_l(w), Q(v, w)], [0, J_l(w)]]"),
    ("jac_right_se3", (("xi", _XI),), lambda: lg.jac_right_se3(_XI), "J_r(xi) = J_l(-xi)"),
)


def angle_calls(M: sp.Matrix) -> tuple[sp.Matrix, list[tuple[sp.Symbol, str, sp.Expr]]]:
    """M with each angle-function call replaced by a symbol named after it; the calls as (symbol, name, s)."""
    calls = sorted(M.atoms(SafeFunctionBase), key=sp.default_sort_key)
    table = []
    for call in calls:
        name = type(call).__name__.removeprefix("angle_")
        if name not in ANGLES or type(call) is not ANGLES[name]:
            raise ValueError(f"{type(call).__name__}: not an angle function of mechgen.symbolic.liegroup")
        table.append((sp.Symbol(f"g_{name}"), name, call.args[0]))
    return M.xreplace({c: sym for c, (sym, _, _) in zip(calls, table)}), table


def _body(M: sp.Matrix, printer) -> tuple[list[str], list[tuple[int, int, str]]]:
    """Assignment lines (angle calls, then CSE temporaries) and the nonzero entries (row, col, text)."""
    M, table = angle_calls(M)
    lines = []
    s_names = {}
    for sym, name, s in table:
        if s not in s_names:
            s_names[s] = f"s{len(s_names)}"
            lines.append(f"{s_names[s]} = {printer.doprint(s)}")
        lines.append(f"{sym} = angle({name!r}, {s_names[s]})")
    cells = [(i, j) for i in range(M.rows) for j in range(M.cols) if M[i, j] != 0]
    temps, reduced = sp.cse([M[i, j] for i, j in cells], symbols=sp.numbered_symbols("x"), order="canonical")
    lines += [f"{sym} = {printer.doprint(e)}" for sym, e in temps]
    return lines, [(i, j, printer.doprint(e)) for (i, j), e in zip(cells, reduced)]


def _unpack(inputs, index: str) -> list[str]:
    return [f"{', '.join(str(s) for s in syms)} = {', '.join(index.format(name=n, k=k) for k in range(len(syms)))}"
            for n, syms in inputs]


def numpy_function(name: str, inputs, M: sp.Matrix, doc: str) -> list[str]:
    """``def name(*inputs, angle)``: the entries over the inputs' leading axes, shape (..., rows, cols)."""
    lines, cells = _body(M, NumpyPrinter())
    args = ", ".join(n for n, _ in inputs)
    first = inputs[0][0]
    out = [f"def {name}({args}, angle):",
           f'    """{doc} (shape (..., {M.rows}, {M.cols})); angle(name, s): the angle functions of s = w.w."""']
    out += ["    " + t for t in _unpack(inputs, "{name}[..., {k}]")]
    out += ["    " + t for t in lines]
    shapes = " + ".join([f"np.broadcast_shapes({', '.join(f'{n}.shape[:-1]' for n, _ in inputs)})"]
                        if len(inputs) > 1 else [f"{first}.shape[:-1]"])
    out.append(f"    out = np.zeros({shapes} + ({M.rows}, {M.cols}))")
    out += [f"    out[..., {i}, {j}] = {text}" for i, j, text in cells]
    return out + ["    return out", "", ""]


def casadi_function(name: str, inputs, M: sp.Matrix, doc: str) -> list[str]:
    """``def name(*inputs, angle)``: the entries as a dense SX matrix (inputs SX column vectors)."""
    lines, cells = _body(M, CasadiPrinter())
    args = ", ".join(n for n, _ in inputs)
    out = [f"def {name}({args}, angle):",
           f'    """{doc} ({M.rows} x {M.cols} SX); angle(name, s): the angle functions of s = w.w."""']
    out += ["    " + t for t in _unpack(inputs, "{name}[{k}]")]
    out += ["    " + t for t in lines]
    out.append(f"    out = ca.SX.zeros({M.rows}, {M.cols})")
    out += [f"    out[{i}, {j}] = {text}" for i, j, text in cells]
    return out + ["    return out", "", ""]


def _closed_functions(printer) -> list[str]:
    out = []
    for name, cls in ANGLES.items():
        s = sp.Symbol("s", positive=True)
        closed = cls(s).closed().subs(s, _T**2)
        out += [f"def closed_{name}(t):", f'    """{name} at the angle t > 0: {closed}."""',
                f"    return {printer.doprint(closed)}", "", ""]
    return out


def _tables() -> list[str]:
    below = {cls.series_below() for cls in ANGLES.values()}
    if len(below) != 1:
        raise ValueError("the angle functions' series intervals differ")
    out = ["#: the series interval of every angle function, s = t^2 < SERIES_BELOW",
           f"SERIES_BELOW = {float(below.pop())!r}",
           "#: the Taylor coefficients c_k of each angle function, a(s) = sum_k c_k s^k", "COEFFS = {"]
    for name, cls in ANGLES.items():
        out.append(f"    {name!r}: ({', '.join(repr(float(c)) for c in cls.coefficients())}),")
    return out + ["}", "", ""]


def _module(title: str, imports: list[str], printer, function) -> str:
    head = ['"""' + title, "",
            "Generated by `mechgen regen` from mechgen/symbolic/liegroup.py (mechgen.codegen.lower_liegroup);",
            "never edit by hand: `mechgen regen --check` fails when this text is not what regen writes.", '"""',
            *imports, "", ""]
    body = _tables() + _closed_functions(printer)
    for name, inputs, build, doc in MAPS:
        body += function(name, inputs, build(), doc)
    return "\n".join(head + body).rstrip() + "\n"


def numpy_module() -> str:
    """The text of mechgen/generated/liegroup/numpy_maps.py."""
    return _module("Batched numpy so(3)/se(3) maps (leading axes are the batch).", ["import numpy as np"],
                   NumpyPrinter(), numpy_function)


def casadi_module() -> str:
    """The text of mechgen/generated/liegroup/casadi_maps.py."""
    return _module("CasADi SX so(3)/se(3) maps (one point; inputs SX column vectors).",
                   ["import casadi as ca", "import numpy as np  # noqa: F401 - np.inf/np.nan in printed numbers"],
                   CasadiPrinter(), casadi_function)


#: the maps the runtime's C (runtime/csrc/rod_elements.c) calls
C_MAPS = ("exp_so3", "jac_left_so3", "jac_left_so3_inv")


def c_function(name: str, inputs, M: sp.Matrix, doc: str) -> list[str]:
    """``static inline void mgl_name(const double *input..., double *out)``: out row-major, every entry written."""
    lines, cells = _body(M, CPrinter())
    lines = [t.replace("angle('", "mgl_").replace("', ", "(") for t in lines]
    args = ", ".join(f"const double *{n}" for n, _ in inputs)
    out = [f"/* {doc} ({M.rows} x {M.cols}, row-major) */",
           f"static inline void mgl_{name}({args}, double *out) {{"]
    out += [f"    const double {s} = {n}[{k}];" for n, syms in inputs for k, s in enumerate(syms)]
    out += [f"    const double {t};" for t in lines]
    text = {(i, j): e for i, j, e in cells}
    out += [f"    out[{M.cols * i + j}] = {text.get((i, j), '0.0')};" for i in range(M.rows) for j in range(M.cols)]
    return out + ["}", ""]


def _c_angles() -> list[str]:
    out = []
    printer = CPrinter()
    for name, cls in ANGLES.items():
        s = sp.Symbol("s", positive=True)
        coeffs = ", ".join(repr(float(c)) for c in cls.coefficients())
        out += [f"/* {name} of the squared angle s = t^2: its Taylor series below MGL_SERIES_BELOW, its closed form "
                "above */",
                f"static inline double mgl_{name}(double s) {{",
                f"    static const double c[{len(cls.coefficients())}] = {{{coeffs}}};",
                "    if (s < MGL_SERIES_BELOW) {",
                f"        double acc = c[{len(cls.coefficients()) - 1}];",
                f"        for (int k = {len(cls.coefficients()) - 2}; k >= 0; --k) acc = acc * s + c[k];",
                "        return acc;", "    }",
                "    const double t = sqrt(s);",
                f"    return {printer.doprint(cls(s).closed().subs(s, _T**2))};", "}", ""]
    return out


def c_header() -> str:
    """The text of mechgen/generated/liegroup/liegroup_maps.h (included by runtime/csrc/rod_elements.c)."""
    below = {cls.series_below() for cls in ANGLES.values()}.pop()
    head = ["/* so(3) maps for the runtime's C (static inline; row-major 3 x 3).", " *",
            " * Generated by `mechgen regen` from mechgen/symbolic/liegroup.py (mechgen.codegen.lower_liegroup);",
            " * never edit by hand: `mechgen regen --check` fails when this text is not what regen writes.", " */",
            "#include <math.h>", "", f"#define MGL_SERIES_BELOW {float(below)!r}", ""]
    body = _c_angles()
    for name, inputs, build, doc in MAPS:
        if name in C_MAPS:
            body += c_function(name, inputs, build(), doc)
    return "\n".join(head + body).rstrip() + "\n"


def generated_texts() -> dict[str, str]:
    """relative path below mechgen/generated/ -> text, for ``mechgen regen``."""
    return {"liegroup/__init__.py": '"""Generated Lie-group maps (mechgen.codegen.lower_liegroup)."""\n',
            "liegroup/numpy_maps.py": numpy_module(), "liegroup/casadi_maps.py": casadi_module(),
            "liegroup/liegroup_maps.h": c_header()}
