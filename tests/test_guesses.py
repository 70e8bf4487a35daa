"""Starting guesses of the runtime (mechgen.runtime.steady.guesses): numpy only, and right by their own geometry."""
import subprocess
import sys

import numpy as np
import pytest

from mechgen.runtime.steady.guesses import loop_count, sine_loop_guesses
from mechgen.symbolic.params import Namespace


def test_guesses_module_imports_no_sympy():
    code = "import sys, mechgen.runtime.steady.guesses; print('sympy' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"


@pytest.mark.parametrize("loops", [1.0, 1.5, 2.0, 3.0])
def test_sine_loop_guesses_have_their_loops_length_and_tension(loops):
    """Each guess runs from the origin to (1, 0, h), has the length l0 (1 + p_g / beta) (measured on the samples),
    n_c = round(loops + 1/2) - 1 axis crossings, and the tension vector p_g t with t the unit tangent of the samples."""
    h, l0, beta, tensions = 10.0, 10.0 / (1 - 0.1), 100.0, (2.0, 5.0, 10.0)
    s = np.linspace(0.0, 1.0, 4001)
    guesses = list(sine_loop_guesses(loops, s, height=h, length=l0, domain=1.0, stiffness=beta, tensions=tensions))
    assert len(guesses) == len(tensions)
    for tension, g in zip(tensions, guesses):
        x, y, z = (np.asarray(g["u"][f]) for f in "xyz")
        assert (x[0], z[0]) == pytest.approx((0.0, 0.0), abs=1e-12) and (x[-1], z[-1]) == pytest.approx((1.0, h))
        assert np.all(y == 0.0)
        assert np.sum(np.hypot(np.diff(x), np.diff(z))) == pytest.approx(l0 * (1 + tension / beta), rel=1e-5)
        n = np.hypot(g["n"]["x"], g["n"]["z"])
        assert n == pytest.approx(np.full_like(n, tension), rel=1e-6)  # unit tangent interpolated linearly
        stretch = np.hypot(g["u_s"]["x"], g["u_s"]["z"])  # uniform: |r_sigma| = l0 lambda_g
        assert stretch == pytest.approx(np.full_like(stretch, l0 * (1 + tension / beta)), rel=1e-5)
        # n_c = round(loops + 1/2) - 1 crossings with the last bulge complete (whether it stays so is the solve's)
        assert loop_count(Namespace({"x": x, "x_s": g["u_s"]["x"]})) == np.floor(loops + 0.5)


def test_loop_count_by_sign_changes():
    """1 without a crossing; n_c + 1 when x falls into the rotating eyelet (x_s < 0 there), n_c + 1/2 otherwise."""
    s = np.linspace(0.0, 1.0, 101)
    cases = [(s + np.sin(np.pi * s), 1 + np.pi * np.cos(np.pi * s), 1.0),             # no crossing
             (s - np.sin(np.pi * s), 1 - np.pi * np.cos(np.pi * s), 1.5),             # one, rising at the end
             (s - 0.8 * np.sin(2 * np.pi * s), 1 - 1.6 * np.pi * np.cos(2 * np.pi * s), 2.0),  # one, falling
             (s + np.sin(3 * np.pi * s), 1 + 3 * np.pi * np.cos(3 * np.pi * s), 3.0)]  # two, falling
    for x, x_s, loops in cases:
        assert loop_count(Namespace({"x": x, "x_s": x_s})) == loops
