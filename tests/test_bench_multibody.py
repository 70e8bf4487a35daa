"""`mechgen bench multibody` (issue 32, item 3): the lattice model against hand-written numpy forces, the suite's
reports from a small run (timings are reported, never asserted), its cap, and - where pydy is installed - PyDy's
side against the pendulum's closed form and the lattice's hand-written forces."""
import csv
import json

import numpy as np
import pytest

import mechgen
from mechgen.bench.multibody import (closed_form_accelerations, growth_exponent, lattice_model, lattice_nodes,
                                     lattice_springs, predicted_seconds, run_multibody_benchmarks)
from mechgen.bench.multibody import sample_states as random_states


def hand_lattice_accelerations(x, rows, cols, m=1.0, k=100.0, a=1.0, g=9.81):
    """The lattice's accelerations written out by hand: each spring pulls its ends with k (|d| - a) d/|d| along
    d = r_b - r_a, gravity -m g in y, anchored nodes (column 0) at rest at (0, -a i)."""
    nodes = lattice_nodes(rows, cols)
    n = 2 * len(nodes)
    index = {node: 2 * s for s, node in enumerate(nodes)}

    def position(i, j):
        rest = np.array([a * j, -a * i])
        return rest if j == 0 else rest + x[index[i, j]:index[i, j] + 2]

    force = np.tile([0.0, -m * g], len(nodes))
    for A, B in lattice_springs(rows, cols):
        d = position(*B) - position(*A)
        pull = k * (np.linalg.norm(d) - a) * d / np.linalg.norm(d)
        for node, sign in ((A, 1.0), (B, -1.0)):
            if node[1] > 0:
                force[index[node]:index[node] + 2] += sign * pull
    return force[:n] / m


def test_lattice_model_matches_hand_written_forces():
    """mechgen's lattice accelerations equal the hand-written spring forces / m at random displaced states to
    1e-12 relative (round-off of sums of O(100) N terms)."""
    system = mechgen.compile(lattice_model(2, 3), kernels=["flow"])
    for x in random_states("lattice", system.n):
        a, _ = system.acceleration(x[:system.n], x[system.n:])
        ref = hand_lattice_accelerations(x[:system.n], 2, 3)
        assert np.allclose(a, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_growth_exponent_and_prediction_of_a_power_law():
    """On t = 0.01 n^2.5 the fitted exponent is 2.5 (sizes below 8 ignored) and the prediction extends it."""
    points = [(n, 0.01 * n**2.5) for n in (2, 4, 8, 16, 32)]
    assert growth_exponent(points) == pytest.approx(2.5, rel=1e-12)
    assert growth_exponent(points[:3]) is None  # only n = 8 at or above 8
    assert predicted_seconds(points, 64) == pytest.approx(0.01 * 64**2.5, rel=1e-12)
    assert predicted_seconds([], 64) == 0.0


def test_small_run_writes_reports_and_skips_over_the_cap(tmp_path):
    """mechgen alone (no PyDy needed): the n = 2 pendulum, its build and its cached rebuild; the n = 64 cell is
    predicted over a 5 s cap from n = 2 and skipped without running; accelerations equal the closed form to 1e-10."""
    data = run_multibody_benchmarks(tmp_path, quick=True, sizes=(2, 64), lattice=(),
                                    tools=("mechgen flow", "mechgen flow cached"), cap_s=5.0)
    pendulum2, pendulum64 = data["rows"]
    assert pendulum2["cells"]["mechgen flow"]["status"] == "ok"
    assert pendulum2["cells"]["mechgen flow cached"]["build_s"] > 0
    assert pendulum64["cells"]["mechgen flow"]["status"].startswith("skipped (> cap")
    assert pendulum64["cells"]["mechgen flow cached"]["status"] == "skipped (no first build)"
    # the closed form's 2 x 2 solve and mechgen's differ by round-off only
    assert pendulum2["agreement"]["reference"] == "closed form" and pendulum2["agreement"]["within_1e-10"]
    assert "end" in pendulum2["cells"]["mechgen flow"]["simulation"]
    rows = list(csv.DictReader((tmp_path / "multibody_results.csv").open()))
    assert [(r["size"], r["tool"]) for r in rows][:2] == [("2", "mechgen flow"), ("2", "mechgen flow cached")]
    assert json.loads((tmp_path / "multibody_results.json").read_text())["tools"] == list(data["tools"])
    text = (tmp_path / "multibody_results.md").read_text()
    assert "First build" in text and "skipped (> cap" in text
    assert "| derive | lower | emit | build | declare | rewrite | cse |" in text


@pytest.mark.parametrize("links, path", [(2, "symbolic"), (9, "ad")])
def test_build_report_times_the_inner_stages_within_the_outer(links, path, tmp_path, monkeypatch):
    """A first build reports declare within derive and, on the symbolic path, rewrite and cse within lower (the
    AD path runs neither: CasADi's program is already shared); the outer stages never exceed the whole."""
    import time

    from mechgen.bench.multibody import pendulum_model
    from mechgen.pipeline import compile_model
    from mechgen.symbolic.specialize import all_free

    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path))
    model = pendulum_model(links)
    start = time.perf_counter()
    _, report = compile_model(model, all_free(model), backend="numpy")
    whole = time.perf_counter() - start
    s = report.seconds
    assert report.origin == "derived" and 0 < s["declare"] <= s["derive"]
    assert sum(s[k] for k in ("derive", "lower", "emit", "build")) <= whole
    if path == "symbolic":
        assert 0 < s["rewrite"] + s["cse"] <= s["lower"]
    else:
        assert "rewrite" not in s and "cse" not in s


@pytest.mark.slow  # two child processes with PyDy's derivation: ~8 s on a loaded 2-core machine
def test_pydy_side_agrees_with_the_references(tmp_path):
    """PyDy Kane + lambdify against the closed form (pendulum, through the suite: accelerations to 1e-10, the
    simulations take the same steps, ends within 1e-9 after 10 s) and the lattice's hand-written forces."""
    pytest.importorskip("pydy")
    from mechgen.bench.multibody import pydy_lattice, pydy_rhs

    rhs = pydy_rhs(pydy_lattice(2, 3, "kane"), "lambdify")
    for x in random_states("lattice", 8):
        ref = hand_lattice_accelerations(x[:8], 2, 3)
        assert np.allclose(rhs(0.0, x)[8:], ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    data = run_multibody_benchmarks(tmp_path, quick=True, sizes=(3,), lattice=(),
                                    tools=("mechgen flow", "PyDy Kane + lambdify"))
    row = data["rows"][0]
    assert row["agreement"]["within_1e-10"], row["agreement"]
    sims = [row["cells"][t]["simulation"] for t in data["tools"]]
    assert sims[0]["nfev"] == sims[1]["nfev"]
    # rtol 1e-8 runs of identical steps: the ends differ by round-off grown over 10 s
    assert row["agreement"]["end_state_difference"]["PyDy Kane + lambdify"] < 1e-9
    assert {r["peer"] for r in json.loads((tmp_path / "multibody_ratios.json").read_text())["ratios"]} == {
        "PyDy Kane + lambdify"}


def test_closed_form_of_a_single_pendulum():
    """n = 1: a = -(g/l) sin(theta)."""
    assert closed_form_accelerations(np.array([0.4]), np.array([2.0]))[0] == pytest.approx(-9.81 * np.sin(0.4))


def test_lambdified_peer_agrees_with_the_closed_form_and_the_numpy_backend():
    """The numpy backend's like-for-like peer (sympy's lambdify of mechgen's own M and h) gives the n-link pendulum's
    closed-form accelerations, as does the numpy backend's one-point path, to 1e-10 (the bench's criterion)."""
    from mechgen.bench.multibody import lambdified_equations, pendulum_model

    n = 4
    peer = lambdified_equations(pendulum_model(n))
    ours = mechgen.compile(pendulum_model(n), backend="numpy", kernels=["flow"])
    for x in random_states("pendulum", n):
        exact = closed_form_accelerations(x[:n], x[n:])
        scale = np.max(np.abs(exact))
        assert np.max(np.abs(peer(0.0, x)[n:] - exact)) < 1e-10 * scale
        assert np.max(np.abs(ours.rhs(0.0, x)[n:] - exact)) < 1e-10 * scale
