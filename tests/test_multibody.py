"""Derivation that scales (issue 32): r = M a + h derived piecewise equals the assembled residual's derivatives, and
the n-link pendulum's accelerations equal its closed-form equations of motion."""
import numpy as np
import pytest
import sympy as sp

import mechgen
from mechgen import models
from mechgen.bench.multibody import pendulum_model
from mechgen.pipeline import derive
from mechgen.symbolic.specialize import all_free


def _lumped_models():
    """Built-in models whose equations are lumped (each mode of a hybrid one), with coordinates."""
    return [name for name in models.names() if not (models.get(name).is_field or models.get(name).is_lattice)
            and models.get(name).coordinate_names]


def _equations(name):
    """The derived equations of the model (of every mode of a hybrid model)."""
    model = pendulum_model(4) if name == "pendulum4" else models.get(name)
    eqs = derive(model, all_free(model))
    return list(eqs.equations) if hasattr(eqs, "equations") else [eqs]


def _numeric(eqs, exprs, rng):
    """Evaluate a list of matrices at one random state and parameter point (same point for every call)."""
    syms = list(eqs.q + eqs.v + eqs.a + eqs.z + eqs.params) + [eqs.t]
    point = dict(zip(syms, rng.uniform(0.5, 1.5, len(syms))))
    return [np.array(sp.Matrix(m).xreplace(point).evalf(), dtype=float) for m in exprs]


@pytest.mark.parametrize("name", _lumped_models() + ["pendulum4"])
def test_split_equals_the_assembled_residuals_derivatives(name):
    """M = dr/da, h = r(a = 0), dr/dq, dr/dv and D, G, K as derived before (differentiating the assembled residual
    and substituting a = 0), at a random point: equal to round-off."""
    for eqs in _equations(name):
        _check_split(eqs)


def _check_split(eqs):
    r, at_rest = eqs.residual, {ai: 0 for ai in eqs.a}
    M, h = eqs.split()
    new = [M, h, eqs.residual_jacobian("q"), eqs.residual_jacobian("v"), *eqs.linear_matrices().values()]
    C = eqs.jacobian(r, "v").subs(at_rest)
    old = [eqs.jacobian(r, "a"), r.subs(at_rest), eqs.jacobian(r, "q"), eqs.jacobian(r, "v"),
           eqs.jacobian(r, "a").subs(at_rest), (C + C.T) / 2, (C - C.T) / 2, eqs.jacobian(r, "q").subs(at_rest)]
    for a, b in zip(_numeric(eqs, new, np.random.default_rng(1)), _numeric(eqs, old, np.random.default_rng(1))):
        assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * (1 + np.abs(b).max()))


def closed_form_accelerations(theta, w, m=1.0, l=1.0, g=9.81):
    """a of the n-link pendulum from its closed-form equations (mechgen.bench.multibody's docstring), written out
    here by hand: sum_j m l^2 c_ij [cos(th_i - th_j) a_j + sin(th_i - th_j) w_j^2] + m g l (n - i) sin th_i = 0."""
    n = len(theta)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    c = n - np.maximum(i, j)
    d = theta[:, None] - theta[None, :]
    M = m * l**2 * c * np.cos(d)
    f = m * l**2 * (c * np.sin(d)) @ (w**2) + m * g * l * (n - np.arange(n)) * np.sin(theta)
    return np.linalg.solve(M, -f)


@pytest.mark.parametrize("n", [3, 9])
def test_pendulum_accelerations_match_the_closed_form(n):
    """The compiled pendulum's accelerations equal the closed form's to 1e-12 (relative) at random states."""
    system = mechgen.compile(pendulum_model(n), kernels=["flow"])
    rng = np.random.default_rng(n)
    for _ in range(3):
        theta, w = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
        a, _ = system.acceleration(theta, w)
        ref = closed_form_accelerations(theta, w)
        assert np.allclose(a, ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())


# -- the AD path (mechgen.symbolic.derive_ad, mechgen.codegen.lower_ad) ----------------------------------------
def _plain_lumped_models():
    """Built-in models the AD path can derive (no modes, coordinates, convertible expressions)."""
    out = []
    for name in _lumped_models():
        model = models.get(name)
        if not model.is_hybrid and model.section_fn is None and model.rod_spec is None:
            out.append(name)
    return out


def _compiled(model, how):
    """The model compiled (numpy backend: no C build) with its equations derived ``how``."""
    before = model.derivation_mode
    try:
        model.derivation(how)
        return mechgen.compile(model, backend="numpy")
    finally:
        model.derivation(before)


@pytest.mark.parametrize("name", _plain_lumped_models())
def test_ad_kernels_equal_the_symbolic_kernels(name):
    """Every kernel of a built-in model derived by AD equals the symbolically derived one at random states (to
    round-off: the two evaluate the same functions in different orders of operations)."""
    model = models.get(name)
    ad, sym = _compiled(model, "ad"), _compiled(model, "symbolic")
    assert set(ad.kernels) == set(sym.kernels)
    if "force" in sym.kernels:  # the splittings' fitness, decided on the declared pieces, agrees
        assert ad.kernels["force"].spec["meta"]["separable"] == sym.kernels["force"].spec["meta"]["separable"]
    rng = np.random.default_rng(7)
    state = {"q": rng.uniform(-1, 1, sym.n), "v": rng.uniform(-1, 1, sym.n), "a": rng.uniform(-1, 1, sym.n),
             "z": rng.uniform(0.5, 1.5, sym.m), "t": 0.3}
    for kernel in sym.kernels:
        wanted = {p["name"] for p in sym.kernels[kernel].spec["inputs"]}
        here = {k: v for k, v in state.items() if k in wanted}
        A, B = ad.call(kernel, **here), sym.call(kernel, **here)
        for port, value in B.items():
            ref = np.asarray(value, float)
            assert np.allclose(np.asarray(A[port], float), ref, rtol=1e-11, atol=1e-11 * (1 + np.abs(ref).max(initial=0))), \
                (kernel, port)


def test_large_models_are_derived_by_ad_and_refused_expressions_fall_back():
    """A 9-link pendulum is derived by AD (9 >= AD_MIN_COORDINATES); a model of as many coordinates whose potential
    holds a Piecewise (not converted to CasADi) is derived symbolically; an unknown derivation is refused."""
    from mechgen.errors import ModelError
    from mechgen.symbolic.derive_ad import AD_MIN_COORDINATES, ADEquations

    big = pendulum_model(9)
    assert 9 >= AD_MIN_COORDINATES and isinstance(derive(big, all_free(big)), ADEquations)
    kinked = pendulum_model(9)
    base = kinked.potential_fn
    kinked.potential_fn = lambda q, p: base(q=q, p=p) + sp.Piecewise((q.theta0**2, q.theta0 > 0), (0, True))
    assert not isinstance(derive(kinked, all_free(kinked)), ADEquations)
    with pytest.raises(ModelError, match="derivation"):
        big.derivation("numeric")


def test_homogeneous_degree_reads_the_tree():
    """Degree 2 of a chain's kinetic energy without expansion; None for a sum of mixed degrees or a function of v."""
    from mechgen.symbolic.derive_ad import homogeneous_degree

    x, y, c = sp.symbols("x y c")
    assert homogeneous_degree(c * (x + 2 * y) ** 2 / 2 + sp.cos(c) * x * y, {x, y}) == 2
    assert homogeneous_degree(x**2 + x, {x, y}) is None
    assert homogeneous_degree(sp.cos(x) * y**2, {x, y}) is None


def test_chain_sums_share_their_prefixes():
    """x_k' = x_{k-1}' + l cos(theta_k) theta_k', flattened by sympy, is rebuilt on the previous sum: the graph of
    the pendulum's kinetic energy grows linearly in n (operations per link constant from 16 to 32 links)."""
    import casadi as ca

    from mechgen.symbolic.derive import declared_lumped
    from mechgen.symbolic.derive_ad import derive_lumped_ad

    counts = []
    for n in (16, 32):
        model = pendulum_model(n)
        eqs = derive_lumped_ad(model, all_free(model), declared_lumped(model, all_free(model)))
        T = ca.Function("T", [eqs.inputs["q"], eqs.inputs["v"], eqs.inputs["p"]], [eqs.pieces["T"]])
        counts.append(T.n_instructions())
    assert counts[1] <= 2.1 * counts[0]


def test_mass_solve_cholesky_with_lu_where_not_positive_definite():
    """mass_solve equals LU's solution for an SPD matrix (to round-off), solves an indefinite one by LU, and a
    singular one raises as numpy's solve does."""
    from mechgen.runtime.core.system import mass_solve

    rng = np.random.default_rng(3)
    A = rng.normal(size=(6, 6))
    b = rng.normal(size=6)
    spd = A @ A.T + 6 * np.eye(6)
    assert np.allclose(mass_solve(spd, b), np.linalg.solve(spd, b), rtol=1e-13, atol=1e-15)
    indefinite = np.diag([1.0, -2.0, 3.0, 1.0, 1.0, 1.0])
    assert np.allclose(mass_solve(indefinite, b), b / np.diag(indefinite), rtol=1e-15)
    with pytest.raises(np.linalg.LinAlgError):
        mass_solve(np.zeros((6, 6)), b)
    assert mass_solve(np.zeros((0, 0)), np.zeros(0)).shape == (0,)


def test_program_text_equals_the_sympy_printers_in_value():
    """mechgen.codegen.program_text prints a program block's operations without sympy; in each dialect every
    operation's text evaluates to the value of sympy's printers on the same operation (operation_expr): C99's
    forms evaluate as Python here (its functions are math's), numpy's on 1-element arrays."""
    import math

    from mechgen.codegen.ir import Operation
    from mechgen.codegen.printing import c_code, math_code, numpy_code
    from mechgen.codegen.program_text import OPERATIONS, operation_expr, operation_text

    binary = [("t0", "t1"), ("t0", 2.5), ("t0", -3.0), (0.125, "t1")]
    constpow = [2.0, 3.0, -2.0, -1.0, 0.5, -0.5, 1.7, 9.0]
    ops = [Operation("t9", op, a) for op in ("add", "sub", "mul", "div", "pow", "atan2", "fmin", "fmax")
           for a in binary]
    ops += [Operation("t9", "constpow", ("t0", e)) for e in constpow]
    domain = {"asin": ("t2", -0.3), "acos": ("t2", -0.3), "atanh": ("t2", -0.3), "acosh": ("t1", 1.5),
              "sqrt": ("t1", 0.4), "log": ("t1", 0.4)}         # arguments where the function is real
    ops += [Operation("t9", op, (a,)) for op in OPERATIONS - {"add", "sub", "mul", "div", "pow", "atan2", "fmin",
                                                                "fmax", "constpow"}
            for a in domain.get(op, ("t1", -0.4, "t2"))]
    assert {o.op for o in ops} == OPERATIONS
    c_names = {k: getattr(math, k) for k in ("sin", "cos", "tan", "exp", "log", "sqrt", "pow", "atan2", "asin",
                                              "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh",
                                              "atanh", "fabs")}
    point = {"t0": 0.7, "t1": 1.3, "t2": 0.4}
    for o in ops:
        value = float(operation_expr(o).subs({sp.Symbol(k, real=True): v for k, v in point.items()}).evalf(20))
        c_scope = {**c_names, "fmin": min, "fmax": max, **point}
        np_scope = {"np": np, **{k: np.array([v]) for k, v in point.items()}}
        for text, scope in ((operation_text(o, "c"), c_scope), (c_code(operation_expr(o)), c_scope),
                            (operation_text(o, "math"), {"math": math, **point}),
                            (math_code(operation_expr(o)), {"math": math, **point}),
                            (operation_text(o, "numpy"), np_scope)):
            got = float(np.asarray(eval(text, scope)).ravel()[0])
            assert math.isclose(got, value, rel_tol=1e-14, abs_tol=1e-15), (o, text, got, value)
        assert numpy_code(operation_expr(o))                    # the sympy numpy printer prints it too


def test_a_large_source_compiled_as_units_gives_the_same_library(monkeypatch, tmp_path):
    """A marked source over UNIT_LINES lines is compiled one kernel per translation unit, several at once, and
    linked: the kernels give the one-unit build's values bit for bit (threshold lowered to 0 so that a 9-link
    pendulum takes that path; its own cache so that it is built, not found)."""
    from mechgen.codegen import build

    model = pendulum_model(9)
    whole = mechgen.compile(model, kernels=["flow", "tangent"])
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path))
    monkeypatch.setattr(build, "UNIT_LINES", 0)
    compiles = build.STATS["compile"]
    split = mechgen.compile(model, kernels=["flow", "tangent"])
    assert build.STATS["compile"] - compiles >= 2                     # one per kernel unit
    x = np.random.default_rng(2).uniform(-1, 1, 18)
    assert np.array_equal(split.rhs(0.0, x), whole.rhs(0.0, x))
    assert np.array_equal(split.jacobian(0.0, x), whole.jacobian(0.0, x))
    assert build.units("int a;\n") is None
    assert build.units(f"#include <math.h>\n{build.UNIT_MARK}\nint f(void);\n{build.UNIT_MARK}\nint g(void);\n") == \
        ["#include <math.h>\n\nint f(void);\n", "#include <math.h>\n\nint g(void);\n"]
