"""``mechgen bench rods`` in quick mode: the reports are written and the static study's numbers hold up.

Independent references: Mattiasson (1981) table 1 at P L^2/EI = 10 for the elliptic-integral solution; the
observed orders of convergence of the two static discretisations (2: Lie-group midpoint collocation; >= 4:
RKMK4 shooting). PyElastica's parts are skipped (the test still runs mechgen's) when pyelastica is missing.
"""
import importlib.util
import json

import pytest

from mechgen.bench import REGISTRY
from mechgen.bench.rods import MATTIASSON_10, REST_TOL, base_section, elastica


def test_elliptic_reference_reproduces_mattiasson():
    u, v, _ = elastica(10.0)
    assert abs(u - MATTIASSON_10[0]) < 6e-6 and abs(-v - MATTIASSON_10[1]) < 6e-6


def test_section_mapping_matches_pyelastica():
    pytest.importorskip("elastica", reason="pyelastica is not installed (the bench extra)")
    from mechgen.bench.rods import ALPHA_C_PIN, pyelastica_section_check

    got = pyelastica_section_check(base_section())
    assert got["alpha_c"] == pytest.approx(ALPHA_C_PIN, rel=1e-14)
    assert max(abs(got[k]) for k in ("EA_rel_diff", "EI_rel_diff", "GJ_rel_diff")) < 1e-14
    assert got["mass_second_moment_over_rho_dl"] == pytest.approx([got["I"], got["I"], got["J"]], rel=1e-14)


@pytest.mark.slow  # the quick benchmark run
def test_quick_run_writes_the_reports(tmp_path):
    res = REGISTRY["rods"].run(tmp_path, quick=True)
    for name in REGISTRY["rods"].reports:
        if name.endswith(".png") and importlib.util.find_spec("matplotlib") is None:
            continue
        assert (tmp_path / name).exists(), name
    st = res["static"]
    assert st["orders"]["mechgen collocation"] == pytest.approx([2.0, 2.0], abs=0.05)
    assert min(st["orders"]["mechgen shooting"]) > 3.8
    assert st["validation"]["reference_self_convergence"] < 2e-6
    assert max(map(abs, st["validation"]["mechgen_shooting_EA_GA_1e8_minus_elliptic"])) < 2e-6
    ratios = json.loads((tmp_path / "rods_ratios.json").read_text())
    if importlib.util.find_spec("elastica") is None:
        assert res["pyelastica"].startswith("skipped") and ratios["ratios"] == []
    else:
        peer = [r for r in st["rows"] if r["side"] == "PyElastica static limit"]
        assert peer and not any(r["blew_up"] for r in peer) and all(r["max_speed_end"] < REST_TOL for r in peer)
        assert ratios["ratios"] and all(r["ratio"] > 0 for r in ratios["ratios"])
    dyn, stiff = res["dynamic"], res["stiff"]
    assert not isinstance(dyn, str) and not isinstance(stiff, str)
    assert all(r["orthonormality_error"] < 1e-12 for r in dyn["rows"])
    # mechgen's coarse runs lie within 3 % of the tip deflection of its fine reference (N = 40 vs 10 here)
    assert all(r["error"] < 3e-2 for r in dyn["rows"])
    # the stiff rod at dt hundreds of times PyElastica's limit: within 2 % of its own dt/4 run
    assert all(r["error"] < 2e-2 and r["dt_over_pyelastica_limit"] > 100 for r in stiff["rows"])
    # the stiff case's common reference (mechgen N = 40, dt = t_end/320 here) has converged: its distances to
    # half the elements and to twice the dt (1.3e-3, 1.0e-3) are at least 5 x below every error compared
    common = stiff["common_reference"]
    compared = [r["error"] for r in stiff["grid"] + stiff.get("pyelastica_ladder", []) if r["error"] is not None]
    assert max(common["self_convergence_half_elements"], common["self_convergence_double_dt"]) < 0.2 * min(compared)
    # mechgen's grid, at dt 280 .. 570 x PyElastica's limit at its N, stays within 2 % of the max deflection of
    # the common reference at 280 x (1.1 .. 1.4 %) and 3 % at 570 x (2.0 .. 2.2 %: the midpoint rule keeps the higher
    # bending modes' amplitudes but not their phase at dt near their periods, plus N = 10's spatial error), with
    # orthonormal frames. (Before issue 30's Newton refresh rule the 570 x runs read 1.1 .. 1.4 % too: Newton
    # failed there and split most steps in halves, a finer dt than the row's.)
    assert all(r["dt_over_pyelastica_limit"] > 100 and r["orthonormality_error"] < 1e-12 for r in stiff["grid"])
    assert all(r["error"] < (2e-2 if r["dt_over_pyelastica_limit"] < 400 else 3e-2) for r in stiff["grid"])
    grav = res["gravity"]
    assert all(r["orthonormality_error"] < 1e-12 and r["error"] < 3e-2 for r in grav["rows"])
    # Newton's counts beside each time; the tip-load and gravity ladders take every step whole (issue 30's
    # refresh rule: no split steps there), the tip-load rows at most 12 solves a step (measured 6.6 and 5.8)
    assert all(r["splits"] == 0 and r["newton_iterations"] <= 12 * round(dyn["t_end"] / r["dt"])
               for r in dyn["rows"]) and all(r["splits"] == 0 for r in grav["rows"])
    # the AD and finite-difference Jacobians of every piece agree to FD's O(sqrt(eps)) error on the same state
    # (the AD ones are exact: tests/test_rod_ad.py holds them to central differences)
    jac = res["jacobians"]["rows"]
    assert {r["piece"] for r in jac} == {"collocation", "shooting", "dynamics step"}
    assert all(r["fd_minus_ad"] < 1e-5 and r["ad_s"] > 0 and r["fd_s"] > 0 for r in jac)
    if importlib.util.find_spec("elastica") is not None:
        # the two codes' trajectories agree to PyElastica's first-order discretisation error (2.2 % at N = 10),
        # and PyElastica refined to N = 20 moves toward mechgen's reference
        assert all(r["agreement_with_pyelastica"] < 3e-2 for r in dyn["rows"])
        peers = dyn["pyelastica"]
        assert peers[1]["error"] < peers[0]["error"] < 3e-2
        # under gravity PyElastica converges at first order in N toward mechgen's reference (11 %, 5 %)
        assert grav["pyelastica_orders"][0] > 0.8 and grav["pyelastica"][-1]["error"] < 0.08
        stable, over = stiff["pyelastica"][:2]
        assert not stable["blew_up"] and over["blew_up"] and over["dt_over_limit"] == 2.0
        # the stiff rod: PyElastica at 0.5 x its limit converges at first order in N toward mechgen's common
        # reference (3.3 %, 1.6 % at N = 10, 20), and mechgen at N = 10 and dt >= 280 x that limit is closer to
        # it than PyElastica at N = 10
        ladder = stiff["pyelastica_ladder"]
        assert not any(r["blew_up"] for r in ladder) and ladder[1]["error"] < ladder[0]["error"] < 5e-2
        assert stiff["pyelastica_orders"][0] > 0.8
        assert all(r["error"] < ladder[0]["error"] for r in stiff["grid"] if r["n"] == ladder[0]["n"])
        m = stiff["matched"]
        assert m["target_error"] == ladder[-1]["error"] and m["mechgen_error"] <= m["target_error"]
        assert m["pyelastica_error"] <= m["target_error"] and m["ratio"] > 0
        assert any(r["peer"] == "PyElastica (stiff, matched accuracy)" for r in ratios["ratios"])
        assert "Matched accuracy" in (tmp_path / "rods.md").read_text().split("## Stiff rod")[1]



def test_every_ratio_is_timed_again_interleaved():
    """The like-for-like rule: a ratio's two runs are timed again as the median of the same number of rounds in
    which they alternate, each side's first call untimed; checked on fake sides whose times are known."""
    from mechgen.bench.rods import interleaved_medians, retimed

    calls, peer_seconds = [], iter([7.0, 1.0, 2.0, 3.0])  # the first, untimed call "takes" 7 s

    def ours():
        calls.append("ours")

    def theirs():
        calls.append("theirs")
        return next(peer_seconds)

    _, peer = interleaved_medians(ours, theirs, 3)
    assert calls == ["ours", "theirs"] * 4 and peer == 2.0
    entry = retimed({"x": 1}, lambda: None, lambda: 0.5, 3)
    assert entry["x"] == 1 and entry["pyelastica_s"] == 0.5 and entry["ratio"] == 0.5 / entry["mechgen_s"]
    assert "interleaved" in entry["statistic"]
