"""The compile pipeline: only needed kernels, constant folding visible in op counts, fallbacks."""
import warnings

import numpy as np
import pytest

import mechgen.pipeline as pipeline
from mechgen import models
from mechgen.codegen import build
from mechgen.pipeline import compile_model
from mechgen.analyses.registry import needs
from mechgen.symbolic.specialize import specialize


def test_only_the_kernels_an_analysis_needs_are_built():
    model = models.get("laval_rotor")
    # modes: M, D, G, K, and the residual that checks the point is an equilibrium; about a steady state
    # (found by it), M, D, G, K alone
    system, report = compile_model(model, specialize(model, {}), kernels=needs("modes", {}, internal=False))
    assert set(report.kernels) == {"linear", "residual"} == set(system.kernels)
    assert needs("modes", {"about": "eq"}, internal=False) == {"linear"}


def test_zero_parameter_disappears_from_the_kernel():
    """c = c_r = 0 fixed by the scene: fewer operations than with damping kept as inputs."""
    model = models.get("laval_rotor")
    _, folded = compile_model(model, specialize(model, {"c": 0.0, "c_r": 0.0}, free=("Omega",)),
                              kernels={"residual", "linear"}, backend="numpy")
    _, kept = compile_model(model, specialize(model, {}, free=("Omega", "c", "c_r")),
                            kernels={"residual", "linear"}, backend="numpy")
    for name in ("residual", "linear"):
        assert folded.kernels[name]["ops"] < kept.kernels[name]["ops"]


def test_second_compile_is_a_cache_hit():
    model = models.get("spring_pendulum")
    spec = specialize(model, {"k": 123.0})
    _, first = compile_model(model, spec, kernels={"residual"}, backend="c")
    _, second = compile_model(model, spec, kernels={"residual"}, backend="c")
    assert not first.cached and second.cached


@pytest.mark.parametrize("backend", ["numpy", "casadi"])
def test_python_backends_hit_the_cache_too(backend):
    model = models.get("spring_pendulum")
    spec = specialize(model, {"k": 77.0})
    compile_model(model, spec, kernels={"force"}, backend=backend)
    _, again = compile_model(model, spec, kernels={"force"}, backend=backend)
    assert again.cached


def test_no_compiler_falls_back_to_numpy_with_one_warning(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    build.reset_compiler_cache()
    monkeypatch.setattr(pipeline, "_warned_no_compiler", False)
    model = models.get("spring_pendulum")
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            system, report = compile_model(model, specialize(model, {"k": 31.0}), kernels={"force"}, backend="c")
            compile_model(model, specialize(model, {"k": 32.0}), kernels={"force"}, backend="c")
    finally:
        build.reset_compiler_cache()
    assert report.backend == "numpy" and system.backend == "numpy"
    assert sum("no C compiler" in str(w.message) for w in caught) == 1
    np.testing.assert_allclose(system.force(np.array([1.0, 0.0])), [-31.0 * 0.0 + 9.81, 0.0])
