"""The runtime's generated Lie-group maps (mechgen/generated/liegroup/) against their sympy source.

Reference: mechgen.symbolic.liegroup evaluated by sympy at the same points in 30-digit arithmetic (its
SafeFunctions' series or closed forms with guard digits), an evaluation path that shares no code with the
printed numpy, CasADi or C text. Points: random axes at angles from 0 through the series switch (1 rad) to
pi and beyond; numpy also batched over two leading axes. And the text committed is what regen writes (the
liegroup part of ``mechgen regen --check``), which changes with the sympy source.
"""
import ctypes

import numpy as np
import pytest
import sympy as sp

from mechgen.codegen import build, lower_liegroup
from mechgen.pipeline import GENERATED
from mechgen.regen import check_generated
from mechgen.runtime.rods import ad
from mechgen.runtime.rods import liegroup as lg
from mechgen.symbolic import liegroup as slg

ANGLES = [0.0, 1e-9, 1e-4, 0.3, 0.999999, 1.0, 1.000001, 2.5, np.pi - 1e-7, np.pi, 5.0]
RTOL = 2e-15


def _points(seed=3):
    rng = np.random.default_rng(seed)
    out = []
    for angle in ANGLES:
        w = rng.normal(size=3)
        w *= angle / np.linalg.norm(w)
        out.append(np.concatenate([rng.normal(size=3), w]))
    return np.array(out)


def _reference(name, xi):
    """The sympy map at xi (a 6-vector: (v, w)), evaluated to 30 digits, as a float array."""
    v, w = [sp.Float(x, 30) for x in xi[:3]], [sp.Float(x, 30) for x in xi[3:]]
    args = {"exp_so3": (w,), "jac_left_so3": (w,), "jac_left_so3_inv": (w,), "q_block": (v, w),
            "exp_se3": (v + w,), "jac_left_se3": (v + w,), "jac_right_se3": (v + w,)}[name]
    return np.array(getattr(slg, name)(*args).evalf(30).tolist(), dtype=float)


def _numpy(name, xi):
    if name == "q_block":
        return lg.q_block(xi[..., :3], xi[..., 3:])
    return getattr(lg, name)(xi[..., 3:] if name.endswith(("so3", "so3_inv")) else xi)


def _close(a, b):
    scale = max(1.0, float(np.max(np.abs(b))))
    assert np.max(np.abs(a - b)) <= RTOL * 10 * scale, (a, b)


@pytest.mark.parametrize("name", [m[0] for m in lower_liegroup.MAPS])
def test_numpy_maps_match_sympy(name):
    xi = _points()
    ref = np.array([_reference(name, x) for x in xi])
    for x, r in zip(xi, ref):
        _close(_numpy(name, x), r)
    batched = _numpy(name, xi.reshape(11, 1, 6) * np.ones((1, 2, 1)))
    for k in range(2):
        _close(batched[:, k], ref)


@pytest.mark.parametrize("name", ["exp_so3", "jac_left_so3", "jac_left_so3_inv", "q_block", "exp_se3"])
def test_casadi_maps_match_sympy(name):
    import casadi as ca

    x = ca.SX.sym("x", 6)
    out = {"exp_so3": lambda: ad.exp_so3(x[3:]), "jac_left_so3": lambda: ad.jac_left_so3(x[3:]),
           "jac_left_so3_inv": lambda: ad.jac_left_so3_inv(x[3:]), "q_block": lambda: ad.q_block(x[:3], x[3:]),
           "exp_se3": lambda: ca.vertcat(ca.horzcat(*ad.exp_se3(x)), ca.DM([[0, 0, 0, 1]]))}[name]()
    f = ca.Function("f", [x], [out])
    for xi in _points(5):
        _close(np.array(f(xi)), _reference(name, xi))


_WRAP = """
void call_{name}(const double *w, double *out) {{ mgl_{name}(w, out); }}
"""


@pytest.mark.skipif(build.find_compiler() is None, reason="no C compiler")
def test_c_maps_match_sympy():
    header = (GENERATED / "liegroup" / "liegroup_maps.h").read_text(encoding="utf-8")
    lib = build.load_shared(header + "".join(_WRAP.format(name=n) for n in lower_liegroup.C_MAPS), stem="mgl_test")
    dbl = ctypes.POINTER(ctypes.c_double)
    for name in lower_liegroup.C_MAPS:
        fn = getattr(lib, f"call_{name}")
        for xi in _points(7):
            w, out = np.ascontiguousarray(xi[3:]), np.zeros(9)
            fn(w.ctypes.data_as(dbl), out.ctypes.data_as(dbl))
            _close(out.reshape(3, 3), _reference(name, xi))


def test_committed_text_is_what_regen_writes():
    for rel, text in lower_liegroup.generated_texts().items():
        assert (GENERATED / rel).read_text(encoding="utf-8") == text, rel


def test_a_changed_sympy_source_makes_the_check_fail(monkeypatch, tmp_path):
    original = lower_liegroup.generated_texts()
    monkeypatch.setattr(slg, "a1_sq", slg.a2_sq)   # a wrong formula in the source
    changed = lower_liegroup.generated_texts()
    assert changed["liegroup/numpy_maps.py"] != original["liegroup/numpy_maps.py"]
    # the check itself, on a copy of the committed liegroup folder and no scenes (no kernels to compare)
    for rel, text in original.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text, encoding="utf-8")
    stale = [s for s in check_generated(tmp_path, scenes=[]) if s.startswith("liegroup")]
    assert any("numpy_maps.py" in s for s in stale), stale
