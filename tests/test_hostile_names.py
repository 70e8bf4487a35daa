"""Names and text from model files on the normal run path (issue 12, section 6).

Text: a choice value (default or set) is part of the specialisation's key, which every emitter
writes into the generated file's docstring or comment. A hostile corpus (C comment terminators,
trigraphs, line splices, NUL, unicode line separators, Python triple quotes and backslashes,
``#include``, template syntax, a very long string) is put through each backend's normal path
(``mechgen.compile``: derive, emit, build or import, call): no code may run -- each payload would
create a sentinel file -- the module must be valid and the kernel must compute f = -k x.

Names: an identifier that equals a name mechgen derives from the model (a velocity, a chain
neighbour, a jet, ...) or reports beside its outputs (built-in outputs, result keys) silently
became that symbol or was overwritten; it is now a ModelError (exit 2) naming the file and the
clash. Where a clash used to give wrong numbers the test also shows the right numbers with a name
that does not clash (closed forms).
"""
from __future__ import annotations

import ast
import re
import shutil
import subprocess

import numpy as np
import pytest

import mechgen
from mechgen.cli import main
from mechgen.codegen.escape import c_comment, code_identifier, py_docstring, py_literal
from mechgen.errors import ModelError
from mechgen.pipeline import generate
from mechgen.symbolic.model import Model
from mechgen.symbolic.names import BUILTIN_OUTPUTS, RESULT_KEYS
from mechgen.symbolic.params import Param
from mechgen.symbolic.specialize import specialize

CC = shutil.which("cc") or shutil.which("gcc")
_C_PAYLOAD = ('__attribute__((constructor)) static void pwn(void) {{ extern int system(const char *); '
              'system("touch {marker}"); }}')
_PY_PAYLOAD = '__import__("os").system("touch {marker}")'
#: name -> hostile text ({marker} is the sentinel's path)
HOSTILE = {
    "c_comment_end": "*/ " + _C_PAYLOAD + " /*",
    "c_trigraph_splice": "*??/\n/ " + _C_PAYLOAD + " /*",
    "c_backslash_splice": "*\\\n/ " + _C_PAYLOAD + " /*",
    "c_comment_start": "/* */ " + _C_PAYLOAD + " /* */",
    "c_include": "\n#include <stdlib.h>\n#define double int\n??=include <stdio.h>",
    "py_triple_double": '"""; ' + _PY_PAYLOAD + '; """',
    "py_triple_single": "'''; " + _PY_PAYLOAD + "; '''",
    "py_escaped_quote": '\\"""; ' + _PY_PAYLOAD + '; #',
    "py_quotes_alone": '"""',
    "py_quote_at_end": 'ends in a quote"',
    "py_backslash": "\\",
    "nul": "a\x00b\x00" + _PY_PAYLOAD,
    "line_separators": "x\u2028" + _PY_PAYLOAD + "\u2029y\x85z\r\n" + _PY_PAYLOAD + "\r",
    "controls": "\x0b\x0c\x1b[2J\x7f",
    "template_syntax": "${HOME} {{ 7*7 }} {% for x in y %}{% endfor %} {# c #} {{ marker }}",
    "unicode": "\u202e bidi \u00e9 \u2713 \U0001f680 \ufeff",
    "very_long": "*/ " * 20000 + '"""' * 20000 + "x" * 100000,
}


def _payload(text: str, marker) -> str:
    return text.replace("{marker}", str(marker))


@pytest.fixture(params=sorted(HOSTILE))
def hostile(request, tmp_path):
    marker = tmp_path / "SENTINEL"
    value = _payload(HOSTILE[request.param], marker)
    model = Model("hostile", doc=value)
    model.params(Param("k", 2.0, value, value), Param("mode", value, value, value, choices=(value, "plain")))
    model.coordinates("x")
    model.kinetic(lambda v: v.x**2 / 2)
    model.potential(lambda q, p: p.k * q.x**2 / 2)
    model.output("stretch", lambda q: q.x, unit=value, doc=value)
    return model, value, marker


@pytest.mark.parametrize("backend", ["numpy", "casadi", "c"])
def test_hostile_choice_values_run_no_code_and_the_kernel_is_right(hostile, backend):
    model, value, marker = hostile
    if backend == "casadi":
        pytest.importorskip("casadi")
    if backend == "c" and CC is None:
        pytest.skip("no C compiler")
    system = mechgen.compile(model, {"k": 3.0, "mode": value}, free=(), backend=backend, kernels=("force",))
    assert not marker.exists()
    np.testing.assert_allclose(system.force(np.array([0.5])), [-1.5], rtol=1e-15)  # f = -k x
    assert not marker.exists()


@pytest.mark.parametrize("backend", ["numpy", "casadi"])
def test_hostile_text_in_python_modules_is_only_docstrings(hostile, backend):
    """The generated module's statements are a docstring, imports, SPEC and functions, the kernels' first
    statement a docstring; no name of the payloads (os, system, __import__) occurs anywhere."""
    model, value, _ = hostile
    text = generate(model, specialize(model, {"mode": value}), ["force"], backend)["text"]
    tree = ast.parse(text)
    assert isinstance(tree.body[0], ast.Expr) and isinstance(tree.body[0].value, ast.Constant)
    kinds = {type(node).__name__ for node in tree.body[1:]}
    assert kinds <= {"Import", "Assign", "FunctionDef"}, kinds
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name.startswith(("mg_", "build_")):  # the kernels
            assert isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} | {n.attr for n in ast.walk(tree)
                                                                         if isinstance(n, ast.Attribute)}
    assert not names & {"os", "system", "__import__", "open", "exec", "eval"}
    assert text.isascii() and "\x00" not in text


def test_hostile_text_in_c_sources_is_only_comments(hostile, tmp_path):
    """Preprocessed, the C source holds only the kernels: no payload survives outside a comment."""
    if CC is None:
        pytest.skip("no C compiler")
    model, value, _ = hostile
    text = generate(model, specialize(model, {"mode": value}), ["force"], "c")["text"]
    assert text.isascii() and "\x00" not in text
    assert [line for line in text.splitlines() if line.lstrip().startswith("#")] == ["#include <math.h>"]
    src = tmp_path / "k.c"
    src.write_text(text.replace("#include <math.h>", ""))  # the kernels as the compiler sees them, minus libm
    done = subprocess.run([CC, "-std=c99", "-E", "-P", str(src)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    code = done.stdout
    assert "__attribute__" not in code and "system" not in code and "pwn" not in code and "/*" not in code
    assert len(re.findall(r"\bint mg_force\(", code)) == 1


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_escapers_give_valid_inert_text(name):
    text = _payload(HOSTILE[name], "/tmp/never")
    doc = py_docstring(text)
    tree = ast.parse(f'"""{doc}"""\n')
    assert len(tree.body) == 1 and isinstance(tree.body[0].value, ast.Constant) and doc.isascii()
    body = c_comment(text)
    assert "*/" not in body and "/*" not in body and "??" not in body and "\\" not in body and body.isascii()
    assert ast.literal_eval(py_literal({"v": [text, 1, 2.5, None, True]})) == {"v": [text, 1, 2.5, None, True]}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_text_is_no_identifier(name):
    text = _payload(HOSTILE[name], "/tmp/never")
    for declare in (lambda: Model(text), lambda: Param(text, 1.0), lambda: Model("m").coordinates(text),
                    lambda: Model("m").output(text, lambda q: 0)):
        with pytest.raises(ModelError):
            declare()
    with pytest.raises(ValueError):
        code_identifier(text)


@pytest.mark.parametrize("value", [float("inf"), float("nan"), object(), {1.5: 1}])
def test_generated_literals_refuse_what_python_cannot_read_back(value):
    with pytest.raises(ValueError):
        py_literal({"x": value})


@pytest.mark.parametrize("name", ["np", "ca", "SPEC", "sizes", "in0", "out3", "mg_force", "nb", "int", "lambda"])
def test_printed_identifiers_never_rebind_the_modules_own(name):
    with pytest.raises(ValueError):
        code_identifier(name)
    assert code_identifier("g12") == "g12" and code_identifier("t3") == "t3"


# ----------------------------------------------------------------------------- names that clash


def _pendulums(first: str, second: str) -> Model:
    """Two pendulums (unit masses and lengths, g = 1) coupled by a spring k = 1 between the bobs (small
    angles): M = I, K = [[1 + k, -k], [-k, 1 + k]], so omega = 1 and sqrt(1 + 2k) = sqrt(3)."""
    model = Model("coupled", file=None)
    model.params(Param("k", 1.0), Param("g", 1.0))
    model.coordinates(first, second)
    model.kinetic(lambda v: (v[0] ** 2 + v[1] ** 2) / 2)
    model.potential(lambda q, p: p.g * (q[0] ** 2 + q[1] ** 2) / 2 + p.k * (q[0] - q[1]) ** 2 / 2)
    return model


@pytest.mark.parametrize("order", [("theta", "theta_dot"), ("theta_dot", "theta"), ("theta", "theta_ddot"),
                                   ("theta_ddot", "theta")])
def test_a_coordinate_named_like_a_velocity_is_refused(order):
    with pytest.raises(ModelError) as info:
        _pendulums(*order)
    assert "theta" in str(info.value) and info.value.key in order


def test_coupled_pendulums_with_names_that_do_not_clash():
    """The model the clash made wrong (frequencies 1.79, 1.79 in the report) gives its closed form."""
    import scipy.linalg

    system = mechgen.compile(_pendulums("theta", "theta_d"), backend="numpy")
    mats = system.linear(np.zeros(2))
    freqs = np.sqrt(scipy.linalg.eigh(mats["K"], mats["M"], eigvals_only=True))
    np.testing.assert_allclose(freqs, [1.0, np.sqrt(3.0)], rtol=1e-12)


def _lumped(*, outputs=(), params=()) -> Model:
    model = Model("clash")
    model.params(Param("k", 2.0), *[Param(p, 1.0) for p in params])
    model.coordinates("x")
    model.kinetic(lambda v: v.x**2 / 2)
    model.potential(lambda q, p: p.k * q.x**2 / 2)
    for name in outputs:
        model.output(name, lambda q: q.x)
    return model


@pytest.mark.parametrize("name", BUILTIN_OUTPUTS + ("iterations", "residual_norm", "coordinates", "t_end",
                                                    "energy_drift", "frequencies", "verdict"))
def test_an_output_named_like_a_builtin_output_or_result_key_is_refused(name):
    assert name in BUILTIN_OUTPUTS or name in RESULT_KEYS
    with pytest.raises(ModelError) as info:
        _lumped(outputs=[name])
    assert info.value.key == name and ("built-in output" in str(info.value) or "result key" in str(info.value))


@pytest.mark.parametrize("params_first", [True, False])
def test_a_parameter_named_like_a_velocity_is_refused_at_declaration(params_first):
    model = Model("clash")
    with pytest.raises(ModelError) as info:
        if params_first:
            model.params(Param("x_dot", 1.0))
            model.coordinates("x")
        else:
            model.coordinates("x")
            model.params(Param("x_dot", 1.0))
    assert info.value.key == ("x" if params_first else "x_dot") and "x_dot" in str(info.value)


def _chain(param: str) -> Model:
    model = Model("chain_clash")
    model.params(Param("N", 8, size=True), Param(param, 1.0))
    model.chain("u", sites="N")
    model.site_kinetic(lambda s: s.v**2 / 2)
    model.bond_potential(lambda a, b, p: p[param] * (b.q - a.q) ** 2 / 2)
    return model


@pytest.mark.parametrize("param", ["u_a", "u_b", "u_a_dot", "u_b_dot", "u_dot", "u_ddot"])
def test_a_chain_parameter_named_like_a_neighbour_is_refused(param):
    with pytest.raises(ModelError) as info:
        mechgen.compile(_chain(param), backend="numpy")
    assert info.value.key in (param, "u") and param in str(info.value)  # "u" when the chain is declared last


def test_a_chain_whose_stiffness_does_not_clash_has_the_closed_form_frequencies():
    """Fixed-fixed chain of N unit masses, bonds kb: omega_j = 2 sqrt(kb) sin(j pi / (2 (N + 1)))."""
    import scipy.linalg

    system = mechgen.compile(_chain("kb"), {"kb": 1.0}, backend="numpy")
    mats = system.linear(np.zeros(8))
    dense = [np.asarray(m.todense()) if hasattr(m, "todense") else np.asarray(m) for m in (mats["K"], mats["M"])]
    freqs = np.sqrt(scipy.linalg.eigh(*dense, eigvals_only=True))
    np.testing.assert_allclose(freqs, 2 * np.sin(np.arange(1, 9) * np.pi / 18), rtol=1e-12)


def _beam(param: str, fields=("w",)) -> Model:
    model = Model("beam_clash")
    model.params(Param("L", 1.0), Param(param, 1.0))
    model.field(*fields, length="L")
    model.kinetic_density(lambda u: sum(u[f + "_t"] ** 2 for f in fields) / 2)
    model.potential_density(lambda u, p: p[param] * sum(u[f + "_ss"] ** 2 for f in fields) / 2)
    return model


@pytest.mark.parametrize("param", ["w_s", "w_ss", "w_t", "w_st", "s", "n_w", "test_w", "test_w_s"])
def test_a_field_parameter_named_like_a_jet_or_derived_symbol_is_refused(param):
    with pytest.raises(ModelError) as info:
        specialize(_beam(param), {})
    assert info.value.key == param and "beam_clash" in str(info.value)


def test_two_fields_whose_jets_clash_are_refused():
    with pytest.raises(ModelError) as info:
        specialize(_beam("EI", fields=("w", "w_s")), {})
    assert info.value.key == "w_s" and "jet w_s of field w" in str(info.value)


@pytest.mark.parametrize("name", ["int", "double", "static", "register", "unsigned"])
def test_c_keywords_are_refused_as_names(name):
    with pytest.raises(ModelError) as info:
        Param(name, 1.0)
    assert "C keyword" in str(info.value)


CLASHING_FILES = {
    "velocity": ("model.coordinates('theta_dot', 'theta')\n", "theta", "theta_dot"),
    "builtin_output": ("model.coordinates('x')\nmodel.output('energy', lambda q: q.x)\n", "energy",
                       "built-in output energy"),
    "result_key": ("model.coordinates('x')\nmodel.output('residual_norm', lambda q: q.x)\n", "residual_norm",
                   "result key residual_norm"),
}


@pytest.mark.parametrize("case", sorted(CLASHING_FILES))
def test_a_model_file_with_a_clashing_name_exits_2_naming_the_file(case, tmp_path, capsys):
    body, key, words = CLASHING_FILES[case]
    path = tmp_path / "clash.py"
    path.write_text("from mechgen import Model, Param\nmodel = Model('clash')\nmodel.params(Param('k', 1.0))\n"
                    + body + "model.kinetic(lambda v: sum(x**2 for x in v) / 2)\n"
                    "model.potential(lambda q, p: p.k * sum(x**2 for x in q) / 2)\n")
    scene = tmp_path / "scene.toml"
    scene.write_text('model = "clash.py"\nbackend = "numpy"\n[[analysis]]\nname = "m"\nkind = "modes"\n')
    code = main(["run", str(scene), "--json", str(tmp_path / "never.json")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert str(path) in err and f"'{key}'" in err and words in err, err
    assert not (tmp_path / "never.json").exists()
