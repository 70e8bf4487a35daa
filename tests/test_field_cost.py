"""Symbolic on the local piece: a continuum's kernels do not depend on the discretisation size.

DESIGN.md: the symbolic cost of a model must not grow with the number of modes or
elements. The generated IR is identical (same signature and operation count) for
5 and 200 basis functions and for 10 and 2000 elements, and so is the time to
derive and lower it (within 2x).
"""
import time

import pytest

from mechgen import models
from mechgen.codegen.lower_model import lower_all
from mechgen.pipeline import derive
from mechgen.symbolic.specialize import specialize


def _build(model, values):
    start = time.perf_counter()
    irs = lower_all(model, derive(model, specialize(model, values)), {"linear", "residual", "tangent"})
    return irs, time.perf_counter() - start


@pytest.mark.parametrize("name,disc,sizes", [("moving_string", "sine", (5, 200)),
                                             ("euler_bernoulli_beam", "hermite", (10, 2000))])
def test_ir_and_derivation_time_do_not_grow_with_size(name, disc, sizes):
    model = models.get(name)
    _build(model, {"discretisation": disc, "N": sizes[0]})  # warm sympy's caches
    small, t_small = _build(model, {"discretisation": disc, "N": sizes[0]})
    large, t_large = _build(model, {"discretisation": disc, "N": sizes[1]})
    assert [ir.signature() for ir in small] == [ir.signature() for ir in large]
    assert [ir.op_count() for ir in small] == [ir.op_count() for ir in large]
    assert t_large < 2 * t_small + 0.05


def test_zero_parameter_folds_terms_away():
    """c = 0 removes the gyroscopic and softening terms of the moving string from the kernel."""
    model = models.get("moving_string")
    moving, _ = _build(model, {"c": 0.7})
    still, _ = _build(model, {"c": 0.0})
    assert still[0].op_count() < moving[0].op_count()
    linear = [ir for ir in still if ir.name == "linear"][0]
    assert not any(w.port == "G" for b in linear.blocks for w in b.writes)


def test_discretisation_names_agree():
    """The scene's choices (symbolic side) are exactly the ones the runtime implements."""
    from mechgen.runtime.fields.discretise import DISCRETISATIONS as RUNTIME
    from mechgen.symbolic.discretisations import DISCRETISATIONS as DECLARED

    assert DECLARED == RUNTIME
