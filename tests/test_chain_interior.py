"""Chain kernels on fixed and periodic ends, with and without an on-site potential.

Reference: derivatives of the whole-chain energy built directly in sympy
(V = sum of bond energies V_b(u_{i+1} - u_i) + sum of on-site energies V_s(u_i),
u_0 = u_{N+1} = 0 for fixed ends, u_{N+1} = u_1 when periodic), for every
backend, with and without CSE, down to N = 1 where a periodic bond joins a
site to itself. The C interior that addresses the CSR data through the
runtime's affine summary (and stores rather than accumulates) must equal the
same kernel run through the slot table alone.
"""
import dataclasses
import functools

import numpy as np
import pytest
import sympy as sp

from mechgen.pipeline import compile_model
from mechgen.runtime.core.pattern import affine_summary, interior
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.specialize import specialize

VALUES = {"gamma": 1.3, "alpha": 0.4, "beta": 0.7, "k0": 0.6, "k4": 0.9}


def _chain(ends: str, onsite: bool) -> Model:
    model = Model(f"chain_{ends}_{'kg' if onsite else 'fpu'}", doc="test chain")
    model.params(Param("N", 4, "", "sites", size=True), Param("gamma", 1.0), Param("alpha", 0.0),
                 Param("beta", 0.0), Param("k0", 0.0), Param("k4", 0.0))
    model.chain("u", sites="N", ends=ends)

    @model.site_kinetic
    def kinetic(s):
        return s.v**2 / 2

    if onsite:
        @model.site_potential
        def onsite_potential(s, p):
            return p.k0 * s.q**2 / 2 + p.k4 * s.q**4 / 4

    @model.bond_potential
    def bond(a, b, p):
        r = b.q - a.q
        return p.gamma * r**2 / 2 + p.alpha * r**3 / 3 + p.beta * r**4 / 4

    return model


def _whole_chain(n: int, ends: str, onsite: bool):
    u = sp.symbols(f"u1:{n + 1}", real=True)
    ext = (0,) + u + (0,) if ends == "fixed" else u + (u[0],)
    g, a, b, k0, k4 = (VALUES[k] for k in ("gamma", "alpha", "beta", "k0", "k4"))
    V = sum(g * r**2 / 2 + a * r**3 / 3 + b * r**4 / 4 for r in (ext[i + 1] - ext[i] for i in range(len(ext) - 1)))
    if onsite:
        V += sum(k0 * x**2 / 2 + k4 * x**4 / 4 for x in u)
    return u, sp.Matrix([V]).jacobian(sp.Matrix(u)), sp.hessian(V, u)


@functools.lru_cache(maxsize=None)
def _system(ends, onsite, backend, cse, n):
    """The compiled chain, built once per arguments in this module (several tests read the same C systems; the
    tests only call them, and test_affine_interior_equals_slot_table puts back the pattern it swaps)."""
    model = _chain(ends, onsite)
    spec = specialize(model, {"N": n, **VALUES})
    return compile_model(model, spec, backend=backend, cse=cse)[0]


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
@pytest.mark.parametrize("cse", [True, False])
@pytest.mark.parametrize("onsite", [False, True])
@pytest.mark.parametrize("ends", ["fixed", "periodic"])
def test_chain_kernels_match_whole_chain(ends, onsite, cse, backend):
    rng = np.random.default_rng(5)
    for n in ((1, 2, 3, 7) if backend == "c" else (1, 2, 5)):
        system = _system(ends, onsite, backend, cse, n)
        u, grad, hess = _whole_chain(n, ends, onsite)
        q, v, a = rng.uniform(-0.7, 0.7, n), rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
        values = dict(zip(u, q))
        g = np.array(grad.subs(values).evalf(), float).ravel()
        H = np.array(hess.subs(values).evalf(), float)
        np.testing.assert_allclose(system.force(q), -g, rtol=1e-12, atol=1e-13, err_msg=f"force N={n}")
        np.testing.assert_allclose(system.residual(q, v, a), a + g, rtol=1e-12, atol=1e-13)
        lin = system.linear(q, v)
        np.testing.assert_allclose(lin["K"].toarray(), H, rtol=1e-12, atol=1e-13, err_msg=f"K N={n}")
        np.testing.assert_allclose(lin["M"].toarray(), np.eye(n), atol=0)
        tan = system.call("tangent", q=q, v=v, a=a)
        np.testing.assert_allclose(tan["r_q"].toarray(), H, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(tan["r_a"].toarray(), np.eye(n), atol=0)
        K = system.call("stiffness", q=q)["K"].toarray()
        np.testing.assert_allclose(K, H, rtol=1e-12, atol=1e-13, err_msg=f"stiffness N={n}")


def _without_affine(pattern):
    """The same pattern with every affine summary emptied: the kernel then uses the slot table alone."""
    slots = {k: (np.zeros_like(v) if k.endswith("_affine") else v) for k, v in pattern.slots.items()}
    return dataclasses.replace(pattern, slots=slots)


@pytest.mark.parametrize("onsite", [False, True])
@pytest.mark.parametrize("ends", ["fixed", "periodic"])
def test_affine_interior_equals_slot_table(ends, onsite):
    rng = np.random.default_rng(9)
    for n in (1, 2, 3, 4, 5, 8, 41):
        system = _system(ends, onsite, "c", True, n)
        for kernel in ("tangent", "linear", "stiffness"):
            q = rng.uniform(-0.5, 0.5, (3, n))
            pattern = system.pattern(kernel)
            run = pattern.slots["slots1_affine" if "slots1_affine" in pattern.slots else "slots0_affine"]
            fast = [system.call(kernel, q=x) for x in q]
            system.patterns[kernel] = _without_affine(pattern)
            try:
                slow = [system.call(kernel, q=x) for x in q]
            finally:
                system.patterns[kernel] = pattern
            for f, s in zip(fast, slow):
                for port in f:
                    np.testing.assert_allclose(f[port].toarray(), s[port].toarray(), rtol=1e-14, atol=1e-15,
                                               err_msg=f"{kernel}.{port} N={n} run={run.tolist()}")


def test_affine_summary_covers_the_interior_of_a_banded_pattern():
    system = _system("fixed", False, "c", True, 50)
    spec, pattern = system.kernels["stiffness"].spec, system.pattern("stiffness")
    recipe = spec["slots"][0]
    a, b, stride, *rest = pattern.slots[recipe["affine"]].tolist()
    assert (a, b) == interior(51, 50, *recipe["offsets"]) and stride == 3
    zlo, zhi = rest[-2:]
    assert (zlo, zhi) == (0, 3 * 50 - 2)       # the interior stores every entry of the tridiagonal K


def test_affine_summary_is_withheld_when_positions_repeat():
    """A run whose stored positions repeat (or a non-affine table) must fall back to the slot table."""
    recipe = {"count": {"const": 6, "terms": []}, "sites": {"const": 6, "terms": []}, "boundary": "zero",
              "entries": [[0, 0]], "offsets": [0, 0], "stored": [{"entries": [0], "carried": []}]}
    repeated = np.array([0, 1, 1, 2, 3, 4])
    out = affine_summary(recipe, repeated, {})
    assert out[0] == 0 or out[1] - out[0] < 6           # the run stops where the step changes
    a, b, stride = out[:3]
    assert len(set(out[3] + stride * np.arange(a, b))) == b - a
    duplicate = dict(recipe, entries=[[0, 0], [0, 0]], stored=[{"entries": [0, 1], "carried": []}])
    table = np.stack([np.arange(6), np.arange(6)], axis=1)
    assert not affine_summary(duplicate, table, {}).any()


def test_batched_sparse_kernel_matches_single_states():
    system = _system("periodic", True, "c", True, 9)
    q = np.random.default_rng(2).uniform(-0.5, 0.5, (7, 9))
    k = system.kernels["stiffness"]
    pattern = system.pattern("stiffness")
    batch = k.evaluate({"q": q, "v": np.zeros_like(q), "p": system.params, **pattern.slots},
                       system.sizes("stiffness"))["K"]
    single = np.array([system.call("stiffness", q=x)["K"].data for x in q])
    np.testing.assert_array_equal(batch, single)


@pytest.mark.parametrize("onsite", [False, True])
@pytest.mark.parametrize("ends", ["fixed", "periodic"])
def test_c_kernels_define_every_output_entry(ends, onsite):
    """Outputs the C interior stores are zeroed elsewhere by the kernel itself: stale values never leak."""
    rng = np.random.default_rng(4)
    for n in (1, 2, 3, 6, 17):
        system = _system(ends, onsite, "c", True, n)
        for name, kernel in system.kernels.items():
            sizes = system.sizes(name)
            inputs = {p["name"]: (system.params if p["name"] == "p" else system.pattern(name).slots[p["name"]]
                                  if p["integer"] else rng.uniform(-0.5, 0.5, n)) for p in kernel.spec["inputs"]}
            expected = kernel.evaluate(inputs, sizes)
            outputs = {k: np.full_like(v, np.nan) for k, v in expected.items()}
            kernel.bind(inputs, outputs, sizes)()
            for port, value in expected.items():
                np.testing.assert_array_equal(outputs[port], value, err_msg=f"{name}.{port} N={n}")


@pytest.mark.parametrize("ends", ["fixed", "periodic"])
def test_recomputed_bond_values_equal_the_numpy_kernel_exactly(ends):
    """The C interior recomputes the previous bond's value instead of carrying it in a register (so GCC can
    vectorise the loop): the same operations, so the force equals the numpy backend's (the same operations on
    arrays) bit for bit, for one state and a batch, on fixed and periodic chains."""
    model = _chain(ends, onsite=False)
    spec = specialize(model, {"N": 1000, **VALUES})
    c, _ = compile_model(model, spec, kernels={"force"}, backend="c")
    py, _ = compile_model(model, spec, kernels={"force"}, backend="numpy")
    rng = np.random.default_rng(5)
    for u in (rng.normal(scale=0.3, size=1000), rng.normal(scale=0.3, size=(7, 1000))):
        fc, fp = c.call("force", q=u)["f"], py.call("force", q=u)["f"]
        assert np.array_equal(fc, fp)


def test_native_tuning_builds_another_library_with_the_same_values(monkeypatch):
    """$MECHGEN_NATIVE=1 builds for the host processor (-march=native, no FMA contraction), under another build key
    that names the processor: the force equals the portable build's ($MECHGEN_NATIVE=0) bit for bit."""
    from mechgen.codegen import build

    model = _chain("fixed", onsite=False)
    spec = specialize(model, {"N": 2000, **VALUES})
    u = np.random.default_rng(6).normal(scale=0.3, size=(3, 2000))
    probe = "double mg_probe(double x);\ndouble mg_probe(double x) { return 2.0 * x; }\n"
    monkeypatch.setenv(build.NATIVE_ENV, "0")
    assert build.native_tuning() == ((), ())
    default, _ = compile_model(model, spec, kernels={"force"}, backend="c")
    generic = build.build_shared(probe, stem="native_probe")
    monkeypatch.setenv(build.NATIVE_ENV, "1")
    assert build.native_tuning() == (build.NATIVE_FLAGS, (build.processor_identity(),))
    assert build.build_shared(probe, stem="native_probe") != generic      # another cache entry
    native, _ = compile_model(model, spec, kernels={"force"}, backend="c")
    assert np.array_equal(native.call("force", q=u)["f"], default.call("force", q=u)["f"])


def test_the_host_tuning_is_the_default_where_the_processor_names_its_instructions(monkeypatch):
    """Unset, $MECHGEN_NATIVE means the host tuning where /proc/cpuinfo names the instruction sets (two processors
    that differ in them never share a build key), and a portable build where it does not; a compiler that rejects
    the flags gets the portable build too."""
    from mechgen.codegen import build

    monkeypatch.delenv(build.NATIVE_ENV, raising=False)
    tuned = (build.NATIVE_FLAGS, (build.processor_identity(),))
    assert build.native_tuning() == (tuned if build.processor_names_its_instructions() else ((), ()))
    monkeypatch.setattr(build, "processor_identity", lambda: "arm64 | arm")
    assert not build.processor_names_its_instructions() and build.native_tuning() == ((), ())


def test_a_compiler_that_rejects_the_host_tuning_builds_portably(tmp_path, monkeypatch):
    """CC rejects -march=native (an old or cross compiler): the build is done portably, the compiler is not taken
    for unusable (no numpy fallback), and the probe runs only once a build has failed."""
    import ctypes
    import shutil

    from mechgen.codegen import build

    real = shutil.which("cc") or shutil.which("gcc")
    if real is None:
        pytest.skip("no C compiler")
    fake = tmp_path / "oldcc"
    fake.write_text(f'#!/bin/sh\nfor a in "$@"; do [ "$a" = "-march=native" ] && '
                    f'{{ echo "oldcc: unrecognized option $a" >&2; exit 1; }}; done\nexec {real} "$@"\n')
    fake.chmod(0o755)
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(fake))
    monkeypatch.setenv(build.NATIVE_ENV, "1")
    build.reset_compiler_cache()
    try:
        probe = "double mg_probe(double x);\ndouble mg_probe(double x) { return 3.0 * x; }\n"
        lib = build.load_shared(probe, stem="oldcc_probe")
        lib.mg_probe.restype, lib.mg_probe.argtypes = ctypes.c_double, [ctypes.c_double]
        assert lib.mg_probe(2.0) == 6.0
        monkeypatch.setenv(build.NATIVE_ENV, "0")  # the portable build's entry is the one that was made: a hit
        compiles = build.STATS["compile"]
        assert build.build_shared(probe, stem="oldcc_probe").is_file() and build.STATS["compile"] == compiles
    finally:
        build.reset_compiler_cache()
