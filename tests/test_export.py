"""``mechgen export``: standalone C and CasADi Functions, checked against mechgen's own kernels.

References: the Python path -- the numpy backend of :func:`mechgen.pipeline.compile_model`
for the same specialisation (its kernels, and :func:`mechgen.runtime.core.pattern.build_pattern`
for a chain's CSR pattern and slot tables) -- and, for the CasADi integrator,
scipy's ``solve_ivp`` over mechgen's own first-order right-hand side ``System.rhs``.
The C files are compiled warning-free (``-std=c99 -Wall -Wextra -pedantic -Werror``) with
a driver the test writes, run, and their printed outputs compared to 1e-12.
"""
import json
import os
import re
import shlex
import shutil
import subprocess
import textwrap
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sps

from mechgen import models
from mechgen.cli import main
from mechgen.codegen.escape import c_comment, py_docstring
from mechgen.errors import InputError
from mechgen.pipeline import compile_model
from mechgen.symbolic.specialize import specialize

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler")
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror"]
HOSTILE_C = '*/ __attribute__((constructor)) static void pwn(void) { puts("PWNED"); } /* ??/\n*??/\n/ \\\n'
HOSTILE_PY = '"""; __import__("os").system("touch {marker}"); """ \\'


def _export(tmp_path, ref, backend, *extra):
    out = tmp_path / f"out_{backend}"
    rc = main(["export", str(ref), "--backend", backend, "--out", str(out), *extra])
    assert rc == 0
    return out


def _numpy_system(ref, values=None):
    model = models.load_model(ref)
    values = values or {}
    free = tuple(p.name for p in model.param_list if p.is_numeric and p.name not in values)
    return model, compile_model(model, specialize(model, values, free=free), backend="numpy")[0]


def _c_array(name, arr, ctype="double"):
    vals = ", ".join(repr(float(x)) if ctype == "double" else str(int(x)) for x in np.ravel(arr)) or "0"
    return f"static const {ctype} {name}[] = {{ {vals} }};"


def _print(name, ptr, length):
    return (f'printf("{name}"); for (long i = 0; i < {length}; ++i) printf(" %.17g", (double){ptr}[i]); '
            'printf("\\n");')


def _run_c(folder, model, main_body, tmp_path):
    """Compile the export and a driver whose main is ``main_body``; return {name: array} of what it prints."""
    driver = folder / "driver.c"
    driver.write_text(f'#include <stdio.h>\n#include <stdlib.h>\n#include "{model}.h"\n\n'
                      f"int main(void)\n{{\n{textwrap.indent(main_body, '    ')}\n    return 0;\n}}\n")
    exe = tmp_path / f"driver_{model}"
    done = subprocess.run([CC, *CFLAGS, "-o", str(exe), str(folder / f"{model}.c"), str(driver), "-lm"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and not done.stderr, done.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=True, cwd=tmp_path)
    out = {}
    for line in run.stdout.splitlines():
        name, *vals = line.split()
        out[name] = np.array([float(v) for v in vals])
    return out, run.stdout


def _dense_kernel_driver(model, kernel, spec, inputs, nbatch):
    """Driver block calling MODEL_KERNEL(nbatch, in..., out...) and printing every output as KERNEL.PORT."""
    lines, args = [], [str(nbatch)]
    for port in spec["inputs"]:
        lines.append(_c_array(f"in_{port['name']}", inputs.get(port["name"], np.zeros(0))))
        args.append(f"in_{port['name']}")
    for port in spec["outputs"]:
        lines.append(f"static double out_{port['name']}[{max(nbatch * port['extent']['const'], 1)}];")
        args.append(f"out_{port['name']}")
    lines.append(f'printf("rc %d\\n", {model}_{kernel}({", ".join(args)}));')
    lines += [_print(f"{kernel}.{p['name']}", f"out_{p['name']}", nbatch * p["extent"]["const"])
              for p in spec["outputs"]]
    return "{\n" + textwrap.indent("\n".join(lines), "    ") + "\n}"


def _compare_dense(kernels, model, folder, tmp_path, rng, nbatch):
    """Run every kernel of ``kernels`` (name -> Python-path Kernel) in C at random inputs; compare; count entries."""
    body, expected = [], {}
    for name, kernel in kernels.items():
        spec = kernel.spec
        inputs = {port["name"]: rng.uniform(0.5, 1.5, (nbatch, port["extent"]["const"]) if port["batched"]
                                            else port["extent"]["const"]) for port in spec["inputs"]}
        expected[name] = {k: np.asarray(v).reshape(nbatch, -1) for k, v in kernel.evaluate(inputs).items()}
        body.append(_dense_kernel_driver(model, name, spec, inputs, nbatch))
    got, _ = _run_c(folder, model, "\n".join(body), tmp_path)
    assert np.all(got["rc"] == 0)
    compared = 0
    for name, outs in expected.items():
        for port, want in outs.items():
            have = got[f"{name}.{port}"].reshape(nbatch, -1)
            scale = max(np.max(np.abs(want), initial=0.0), 1.0)
            np.testing.assert_allclose(have, want, rtol=1e-12, atol=1e-12 * scale, err_msg=f"{name}.{port}")
            compared += want.size
    return compared


@needs_cc
def test_c_export_of_the_laval_rotor_matches_the_python_kernels(tmp_path):
    folder = _export(tmp_path, "laval_rotor", "c")
    header = (folder / "laval_rotor.h").read_text()
    assert "q[0] x, q[1] y, q[2] theta_x, q[3] theta_y" in header
    assert "p[5] Omega [rad/s]: spin speed" in header
    assert "out_M [16]: mass matrix M = dr/da; 4 x 4 row-major, symmetric" in header
    _, system = _numpy_system("laval_rotor")
    rng = np.random.default_rng(11)
    assert _compare_dense(system.kernels, "laval_rotor", folder, tmp_path, rng, nbatch=3) > 100


@needs_cc
def test_c_export_folds_set_values(tmp_path):
    folder = _export(tmp_path, "laval_rotor", "c", "--set", "Omega=250", "--set", "m=3.5", "--kernels", "linear")
    header = (folder / "laval_rotor.h").read_text()
    assert "Omega = 250" in header and "p[0] Ip" in header and "laval_rotor_residual" not in header
    _, system = _numpy_system("laval_rotor", {"Omega": 250.0, "m": 3.5})
    rng = np.random.default_rng(12)
    assert _compare_dense({"linear": system.kernels["linear"]}, "laval_rotor", folder, tmp_path, rng, nbatch=2) > 30


@needs_cc
def test_c_export_of_a_continuum_s_pointwise_kernels_batched_over_points(tmp_path):
    folder = _export(tmp_path, "euler_bernoulli_beam", "c")
    header = (folder / "euler_bernoulli_beam.h").read_text()
    assert "jets at the point: q[0] w, q[1] w_s, q[2] w_ss" in header and "pointwise kernel" in header
    _, system = _numpy_system("euler_bernoulli_beam")
    rng = np.random.default_rng(13)
    assert _compare_dense(system.kernels, "euler_bernoulli_beam", folder, tmp_path, rng, nbatch=5) > 50


def _chain_driver(model, kernel, spec, sites, inputs, nbatch):
    """Driver: nnz and the pattern from the export's own builder, then the kernel; prints all of it."""
    slot_ports = [p for p in spec["inputs"] if p["integer"]]
    lines = [f"const long sites = {sites};"]
    if slot_ports:
        lines += [f"const long nnz = {model}_{kernel}_nnz(sites);",
                  "long *indptr = malloc(sizeof(long) * (size_t)(sites + 1));",
                  "long *indices = malloc(sizeof(long) * (size_t)(nnz > 0 ? nnz : 1));"]
        for p in slot_ports:
            n = p["extent"]["const"] + sum(c * sites for _, c in p["extent"]["terms"])
            lines.append(f"long *{p['name']} = malloc(sizeof(long) * {max(n, 1)});")
        pat = [x for p in slot_ports if not p["name"].endswith("_affine") for x in (p["name"], p["name"] + "_affine")]
        lines.append(f'printf("prc %d\\n", {model}_{kernel}_pattern(sites, indptr, indices, {", ".join(pat)}));')
        lines += [_print("indptr", "indptr", "sites + 1"), _print("indices", "indices", "nnz")]
        for p in slot_ports:
            n = p["extent"]["const"] + sum(c * sites for _, c in p["extent"]["terms"])
            lines.append(_print(p["name"], p["name"], n))
    args = [str(nbatch)] + list(spec["sizes"])
    for p in spec["inputs"]:
        if p["integer"]:
            args.append(p["name"])
        else:
            lines.append(_c_array(f"in_{p['name']}", inputs[p["name"]]))
            args.append(f"in_{p['name']}")
    for p in spec["outputs"]:
        n = "nnz" if p["sparse"] else p["extent"]["const"] + sum(c * sites for _, c in p["extent"]["terms"])
        lines.append(f"double *out_{p['name']} = malloc(sizeof(double) * (size_t)({nbatch} * ({n}) + 1));")
        args.append(f"out_{p['name']}")
    lines.append(f'printf("rc %d\\n", {model}_{kernel}({", ".join(args)}));')
    for p in spec["outputs"]:
        n = "nnz" if p["sparse"] else p["extent"]["const"] + sum(c * sites for _, c in p["extent"]["terms"])
        lines.append(_print(p["name"], f"out_{p['name']}", f"{nbatch} * ({n})"))
    frees = (["indptr", "indices"] if slot_ports else []) + [p["name"] for p in slot_ports]
    frees += [f"out_{p['name']}" for p in spec["outputs"]]
    lines += [f"free({x});" for x in frees]
    return "\n".join(lines)


PERIODIC_CHAIN = """
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("ring", doc="periodic Klein-Gordon-FPU ring")
model.params(Param("N", 4, "", "sites", size=True), Param("gamma", 1.0), Param("alpha", 0.3), Param("k0", 0.6))
model.chain("u", sites="N", ends="periodic")


@model.site_kinetic
def kinetic(s):
    return s.v**2 / 2


@model.site_potential
def onsite(s, p):
    return p.k0 * s.q**2 / 2 + s.q**4 / 4


@model.bond_potential
def bond(a, b, p):
    r = b.q - a.q
    return p.gamma * r**2 / 2 + p.alpha * r**3 / 3
"""


@needs_cc
@pytest.mark.parametrize("sites", [1, 2, 9])
@pytest.mark.parametrize("chain", ["fpu_chain", "ring"])
def test_c_export_of_chain_kernels_and_their_sparsity(tmp_path, sites, chain):
    ref = "fpu_chain"
    if chain == "ring":
        ref = tmp_path / "ring.py"
        ref.write_text(PERIODIC_CHAIN)
        ref = str(ref)
    folder = _export(tmp_path, ref, "c")
    header = (folder / f"{chain}.h").read_text()
    assert f"long {chain}_linear_nnz(long sites);" in header
    model, system = _numpy_system(ref, {"N": sites})
    rng = np.random.default_rng(20 + sites)
    nbatch = 2
    for name, kernel in system.kernels.items():
        spec = kernel.spec
        sizes = system.sizes(name)
        inputs = {p["name"]: rng.uniform(-0.6, 0.6, (nbatch, sizes["sites"]) if p["batched"] else
                                         p["extent"]["const"]) for p in spec["inputs"] if not p["integer"]}
        full = dict(inputs)
        if spec["slots"]:
            full.update(system.pattern(name).slots)
        want = kernel.evaluate(full, sizes)
        got, _ = _run_c(folder, chain, _chain_driver(chain, name, spec, sites, inputs, nbatch), tmp_path)
        assert got["rc"][0] == 0 and got.get("prc", [0])[0] == 0
        if spec["slots"]:
            pattern = system.pattern(name)
            np.testing.assert_array_equal(got["indptr"], pattern.indptr)
            np.testing.assert_array_equal(got["indices"], pattern.indices)
            for port, table in pattern.slots.items():  # slot tables and their affine summaries
                np.testing.assert_array_equal(got[port], table, err_msg=port)
                if port.endswith("_affine") and sites == 9:
                    assert table[1] - table[0] >= 4  # a real affine run, not the all-zero fallback
        for p in spec["outputs"]:
            have = got[p["name"]].reshape(nbatch, -1)
            ref = np.asarray(want[p["name"]]).reshape(nbatch, -1)
            if p["sparse"]:
                pattern = system.pattern(name)
                for b in range(nbatch):
                    mine = sps.csr_matrix((have[b], got["indices"].astype(int), got["indptr"].astype(int)),
                                          shape=(sites, sites)).toarray()
                    np.testing.assert_allclose(mine, pattern.matrix(ref[b]).toarray(), rtol=1e-12, atol=1e-12,
                                               err_msg=f"{name}.{p['name']}")
            else:
                np.testing.assert_allclose(have, ref, rtol=1e-12, atol=1e-12, err_msg=f"{name}.{p['name']}")


def test_casadi_export_integrates_the_laval_rotor_like_mechgen(tmp_path):
    ca = pytest.importorskip("casadi")
    from scipy.integrate import solve_ivp

    folder = _export(tmp_path, "laval_rotor", "casadi", "--set", "c=0.4", "--set", "c_r=0.02", "--set", "c_i=0",
                     "--set", "k_t3=0")
    manifest = json.loads((folder / "laval_rotor.json").read_text())
    res = ca.Function.load(str(folder / manifest["kernels"]["residual"]["file"]))
    tan = ca.Function.load(str(folder / manifest["kernels"]["tangent"]["file"]))
    ins = {p["name"]: p for p in manifest["kernels"]["residual"]["inputs"]}
    assert ins["q"]["entries"] == ["x", "y", "theta_x", "theta_y"]
    assert ins["p"]["entries"] == manifest["free_params"] == ["m", "Ip", "Id", "k_t", "k_r", "Omega"]
    assert manifest["fixed"] == {"c": 0.4, "c_r": 0.02, "c_i": 0.0, "k_t3": 0.0}
    model, system = _numpy_system("laval_rotor", {"c": 0.4, "c_r": 0.02, "c_i": 0.0, "k_t3": 0.0})
    p_val = np.array([2.0, 0.03, 0.02, 4.0e4, 900.0, 120.0])
    system = _with(system, p_val)

    # the loaded functions equal the Python kernels at a random point
    rng = np.random.default_rng(5)
    q, v, a = (rng.uniform(-0.1, 0.1, 4) for _ in range(3))
    want = system.kernels["tangent"].evaluate({"q": q, "v": v, "a": a, "t": [0.3], "p": p_val})
    got = tan(q, v, a, ca.DM(0, 1), 0.3, p_val)
    for k, name in enumerate(["r_q", "r_v", "r_a"]):
        np.testing.assert_allclose(np.asarray(got[k]).ravel(), want[name], rtol=1e-12, atol=1e-9)

    # x' = (v, -M(q)^-1 r(q, v, 0)) with M = dr/da, r(q, v, a = 0) from the loaded functions
    x, p, t = ca.SX.sym("x", 8), ca.SX.sym("p", 6), ca.SX.sym("t")
    zero = ca.SX.zeros(4)
    r0 = res(x[:4], x[4:], zero, ca.SX(0, 1), t, p)
    mass = ca.reshape(tan(x[:4], x[4:], zero, ca.SX(0, 1), t, p)[2], 4, 4).T
    ode = ca.vertcat(x[4:], -ca.solve(mass, r0))
    horizon = 0.08
    times = np.linspace(0.0, horizon, 9)
    F = ca.integrator("F", "cvodes", {"x": x, "p": p, "t": t, "ode": ode}, 0.0, times,
                      {"abstol": 1e-12, "reltol": 1e-11})
    x0 = np.array([1e-3, -5e-4, 2e-3, 1e-3, 0.02, 0.0, -0.1, 0.3])
    traj = np.asarray(F(x0=x0, p=p_val)["xf"])
    ref = solve_ivp(system.rhs, (0.0, horizon), x0, t_eval=times, rtol=1e-11, atol=1e-13, method="DOP853")
    scale = np.max(np.abs(ref.y), axis=1, keepdims=True)
    np.testing.assert_allclose(traj / scale, ref.y / scale, atol=1e-8)
    assert np.max(np.abs(ref.y[:, -1] - x0)) > 1e-3  # the motion is not trivial


def _with(system, values):
    """The numpy system with new free-parameter values (a new system; the old one is not changed)."""
    import dataclasses

    if hasattr(system, "with_params"):
        return system.with_params(**dict(zip(system.meta["params"], values)))
    return dataclasses.replace(system, params=np.asarray(values, float))


def test_casadi_export_of_a_chain_carries_its_pattern(tmp_path):
    ca = pytest.importorskip("casadi")
    folder = _export(tmp_path, "fpu_chain", "casadi", "--set", "N=6", "--kernels", "stiffness,force")
    manifest = json.loads((folder / "fpu_chain.json").read_text())
    assert manifest["sites"] == 6
    assert manifest["kernels"]["force"]["inputs"][0]["entries"] == [f"u_{i}" for i in range(1, 7)]
    k = manifest["kernels"]["stiffness"]
    fn = ca.Function.load(str(folder / k["file"]))
    _, system = _numpy_system("fpu_chain", {"N": 6})
    q = np.random.default_rng(3).uniform(-0.5, 0.5, 6)
    p_val = np.array([1.2, 0.3, 0.6])
    system = _with(system, p_val)
    pat = k["outputs"][0]["pattern"]
    data = np.asarray(fn(q, np.zeros(6), p_val)).ravel()
    mine = sps.csr_matrix((data, pat["indices"], pat["indptr"]), shape=(6, 6)).toarray()
    want = system.kernels["stiffness"].evaluate({"q": q, "p": p_val, **system.pattern("stiffness").slots},
                                                system.sizes("stiffness"))["K"]
    np.testing.assert_allclose(mine, system.pattern("stiffness").matrix(want).toarray(), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("argv, key", [
    (["no_such_model"], "model"),
    (["laval_rotor", "--set", "nosuch=1"], "--set nosuch"),
    (["laval_rotor", "--set", "m=abc"], "--set m"),
    (["laval_rotor", "--set", "m=-1"], "--set m"),
    (["laval_rotor", "--set", "m"], "--set m"),
    (["fpu_chain", "--set", "N=2.5"], "--set N"),
    (["laval_rotor", "--kernels", "linear,bogus"], "--kernels"),
    (["laval_rotor", "--kernels", ","], "--kernels"),
    (["euler_bernoulli_beam", "--set", "bc=no-such-end"], "--set bc"),
    (["spinning_shaft", "--set", "disk_m=2"], "--set disk_m"),
    (["laval_rotor", "--backend", "numpy"], "--backend"),
])
def test_bad_export_input_exits_2_and_writes_nothing(tmp_path, capsys, argv, key):
    out = tmp_path / "out"
    backend = [] if "--backend" in argv else ["--backend", "c"]
    assert main(["export", *argv, *backend, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert key in err and "Traceback" not in err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_out_naming_a_file_exits_2_before_deriving(tmp_path, capsys, monkeypatch):
    import mechgen.pipeline as pipeline

    target = tmp_path / "taken"
    target.write_text("keep me")
    monkeypatch.setattr(pipeline, "derive", lambda *a, **k: pytest.fail("derived before checking --out"))
    assert main(["export", "laval_rotor", "--backend", "c", "--out", str(target)]) == 2
    assert "--out" in capsys.readouterr().err and target.read_text() == "keep me"
    blocked = tmp_path / "dir"
    (blocked / "laval_rotor.h").mkdir(parents=True)
    assert main(["export", "laval_rotor", "--backend", "c", "--out", str(blocked)]) == 2
    assert sorted(p.name for p in blocked.iterdir()) == ["laval_rotor.h"]


def test_out_in_a_read_only_folder_exits_2(tmp_path, capsys, monkeypatch):
    import mechgen.export as export

    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    if os.geteuid() == 0:  # permissions do not bind root: let the folder report itself read-only
        real = os.access
        monkeypatch.setattr(export.os, "access", lambda p, mode: real(p, mode) and Path(p) != locked)
    try:
        assert main(["export", "laval_rotor", "--backend", "c", "--out", str(locked / "out")]) == 2
        assert "not writable" in capsys.readouterr().err and list(locked.iterdir()) == []
    finally:
        locked.chmod(0o755)


def test_a_failure_while_writing_leaves_nothing_half_written(tmp_path, monkeypatch):
    import mechgen.export as export

    out = tmp_path / "out"
    calls = []

    def boom(self, data):
        calls.append(self.name)
        if len(calls) == 2:
            raise OSError("disk full")
        return original(self, data)

    original = export.Path.write_bytes
    monkeypatch.setattr(export.Path, "write_bytes", boom)
    with pytest.raises(OSError):
        export.write_atomically(out, {"a.h": "x", "a.c": "y"})
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    out.mkdir()
    (out / "a.h").write_text("old")
    (out / "a.c").mkdir()  # in the way of the second file: the first is not replaced either
    with pytest.raises(InputError):
        export.write_atomically(out, {"a.h": "new", "a.c": "y"})
    assert (out / "a.h").read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["out"]


# --------------------------------------------------------------------------- hostile text


def test_escapers_neutralise_hostile_text(tmp_path):
    import ast

    text = HOSTILE_C + HOSTILE_PY.format(marker="x") + '"'
    doc = py_docstring(text)
    tree = ast.parse(f'"""{doc}"""\n')
    assert len(tree.body) == 1 and isinstance(tree.body[0].value, ast.Constant)
    body = c_comment(text)
    assert "*/" not in body and "/*" not in body and "??" not in body and "\\" not in body
    if CC:
        src = tmp_path / "c.c"
        src.write_text(f"/*{body}*/\nint mg_only(void);\n")
        done = subprocess.run([CC, "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-E", "-P", str(src)],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        assert "pwn" not in done.stdout and "int mg_only(void);" in done.stdout


HOSTILE_MODEL = '''
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("hostile", doc={doc!r})
model.params(Param("k", 2.0, {unit!r}, {doc!r}, positive=True),
             Param("mode", {choice!r}, "", {doc!r}, choices=({choice!r}, "plain")))
model.coordinates("x")


@model.kinetic
def kinetic(q, v, p):
    return v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2


model.output("stretch", lambda q: q.x, doc={doc!r})
'''


@pytest.mark.parametrize("backend", ["c", "casadi"])
def test_hostile_docs_and_choices_reach_no_code(tmp_path, monkeypatch, backend):
    marker = tmp_path / "PWNED"
    hostile = HOSTILE_C + HOSTILE_PY.format(marker=marker)
    path = tmp_path / "models" / "hostile.py"
    path.parent.mkdir()
    path.write_text(HOSTILE_MODEL.format(doc=hostile, unit="N/m */ int evil; /*", choice=HOSTILE_PY.format(
        marker=marker)))
    monkeypatch.chdir(tmp_path)
    if backend == "casadi":
        pytest.importorskip("casadi")
    folder = _export(tmp_path, path, backend, "--set", "k=3")
    assert not marker.exists()
    if backend == "casadi":
        import casadi as ca

        manifest = json.loads((folder / "hostile.json").read_text())
        assert manifest["doc"].startswith("*/ __attribute__")  # kept verbatim as JSON data
        fn = ca.Function.load(str(folder / manifest["kernels"]["force"]["file"]))
        np.testing.assert_allclose(float(fn([0.5], [0.0], ca.DM(0, 1), 0.0, ca.DM(0, 1))), -1.5, rtol=1e-15)
        assert not marker.exists()
        return
    if CC is None:
        pytest.skip("no C compiler")
    pre = subprocess.run([CC, *CFLAGS, "-E", "-P", str(folder / "hostile.h")], capture_output=True, text=True)
    assert pre.returncode == 0 and not pre.stderr, pre.stderr
    assert "pwn" not in pre.stdout and "evil" not in pre.stdout and "__attribute__" not in pre.stdout
    got, stdout = _run_c(folder, "hostile", "\n".join([
        "static const double q[1] = { 0.5 };", "static double f[1];",
        'printf("rc %d\\n", hostile_force(1, q, NULL, NULL, q, NULL, f));', _print("f", "f", 1)]), tmp_path)
    assert "PWNED" not in stdout and got["f"][0] == -1.5


def _readme_section():
    text = (Path(__file__).resolve().parents[1] / "docs" / "guide.md").read_text()  # moved from the README
    section = text.split("## Export", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```(\w*)\n(.*?)```", section, re.S)
    return [(lang, body) for lang, body in blocks]


@needs_cc
def test_readme_export_examples_run_verbatim(tmp_path, monkeypatch):
    ca = pytest.importorskip("casadi")
    monkeypatch.chdir(tmp_path)
    blocks = _readme_section()
    assert [lang for lang, _ in blocks] == ["", "c", "", "python"]
    for lang, body in blocks:
        if lang == "":
            for line in body.splitlines():
                argv = shlex.split(line, comments=True)
                if argv[:2] == ["mechgen", "export"]:
                    assert main(argv[1:]) == 0
                elif argv:
                    assert argv[0] == "cc"
                    done = subprocess.run([CC, *argv[1:], "-Wall", "-Wextra", "-pedantic", "-Werror"],
                                          capture_output=True, text=True)
                    assert done.returncode == 0 and not done.stderr, done.stderr
        elif lang == "c":
            driver = tmp_path / "readme.c"
            driver.write_text('#include <stddef.h>\n#include <stdio.h>\n#include "export/laval_rotor.h"\n\n'
                              "int main(void)\n{\n" + textwrap.indent(body, "    ")
                              + '    printf("%.17g %.17g\\n", G[11], K[0]);\n    return 0;\n}\n')
            exe = tmp_path / "readme"
            done = subprocess.run([CC, *CFLAGS, "-o", str(exe), str(driver), "laval_rotor.o", "-lm"],
                                  capture_output=True, text=True)
            assert done.returncode == 0 and not done.stderr, done.stderr
            g, k = map(float, subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.split())
            assert g == pytest.approx(0.03 * 300, rel=1e-14) and k == pytest.approx(4e4, rel=1e-14)  # Ip Omega, k_t
        else:
            namespace: dict = {}
            exec(compile(body, "guide.md", "exec"), namespace)
            assert isinstance(namespace["F"], ca.Function)
