"""Bad and extreme scenes end in a clear word, never a traceback or an unbounded wait (issue 12, section 5).

Two parts, both through ``mechgen.cli.main`` (tests/fuzzing.py runs each case in a forked child of this
process with a wall-clock limit and an address-space cap, and judges it):

* the explicit cases of issue 12 section 5, each with the exit code it must end in (2: bad input named at
  the scene key the user wrote; 1: a computation that failed, named);
* a scene fuzzer: the shipped scenes (made cheaper: fewer sweep points, shorter runs) mutated by
  hypothesis (dropped keys, wrong types, huge / negative / zero / NaN / infinite numbers, unknown keys,
  emptied tables, hostile strings, deep nesting, ``--set``), seeded (``derandomize``), ``CI_EXAMPLES``
  cases in every run and ``MECHGEN_FUZZ_EXAMPLES`` more in the opt-in ``slow`` run
  (``MECHGEN_FUZZ_EXAMPLES=3000 pytest -m slow tests/test_fuzz_scenes.py``). A case passes when it exits 0,
  or 2 with a message naming the scene file and a key, or 1 with a named failure, leaving no half-written
  output. Nothing is written outside ``tmp_path`` (and the session's compile cache).

Cases that fail today are marked xfail (not strict) with the area that owns the fix; the fuzz tests are
xfail while ``FUZZ_XFAIL`` is true. Remove the marks (flip the constant) as those fixes land.
"""
from __future__ import annotations

import math
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis.configuration import set_hypothesis_home_dir

from fuzzing import (COMPILE_EXTENSIONS, FAST_SCENES, KILL_GRACE, Case, CaseTimeout, Deep, Outcome, base_doc,
                     case_strategy, check_case, dumps, judge, keys_of, last_message, names_a_key, run_case, set_path,
                     warm_up)

FUZZ_XFAIL = False  # true marks the fuzz runs xfail (while fixes for what it finds are pending)
FUZZ_XFAIL_REASON = "issue 12 section 5: tracebacks and hangs not fixed yet (scene validation, printers, budgets)"
CI_EXAMPLES = 200
CI_LIMIT_S = 10.0  # wall-clock limit of one fuzz case (its cheap base runs in < 1 s once compiled)
EXPLICIT_LIMIT_S = 10.0

pytestmark = pytest.mark.fuzz

# Hypothesis caches the constants of imported modules in its home folder (default: ./.hypothesis) also while
# other test modules are collected after this one: point it at a temporary folder from import on (removed at
# this module's teardown); the fixture below moves it under tmp_path while the tests run.
_COLLECTION_HOME = tempfile.mkdtemp(prefix="mechgen-hypothesis-")
set_hypothesis_home_dir(_COLLECTION_HOME)



@pytest.fixture(scope="module", autouse=True)
def hypothesis_home(tmp_path_factory):
    """Hypothesis's own files (its constants and unicode caches) go under the test's temporary folder, not
    into ``.hypothesis/`` in the current directory (``database=None`` keeps it from storing examples)."""
    set_hypothesis_home_dir(tmp_path_factory.mktemp("hypothesis"))
    yield
    set_hypothesis_home_dir(_COLLECTION_HOME)
    shutil.rmtree(_COLLECTION_HOME, ignore_errors=True)


@pytest.fixture(scope="module")
def warmed(tmp_path_factory):
    """Every fast scene run once unmutated in this process (compiles and imports happen here, once)."""
    return warm_up(FAST_SCENES, tmp_path_factory.mktemp("warm"))


# --- the harness itself -----------------------------------------------------------------------------------------

def test_writer_round_trips_every_shipped_scene():
    try:
        import tomllib
    except ImportError:  # pragma: no cover - Python 3.10
        import tomli as tomllib

    for path in sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.toml")):
        doc = base_doc(path.stem, cheap=False)
        assert tomllib.loads(dumps(doc)) == doc, path.name
    odd = {"a": [math.nan, -0.0, 10**310, 'q"\\\n\x00\u202e', True], "b": {"c d": {}, "": []},
           "t": [{"x": 1}, {"y": {"z": [1, "a"]}}]}
    back = tomllib.loads(dumps(odd))
    assert math.isnan(back["a"][0]) and math.copysign(1.0, back["a"][1]) == -1.0
    assert back["a"][2:] == odd["a"][2:] and back["b"] == odd["b"] and back["t"] == odd["t"]
    deep = tomllib.loads(dumps({"d": Deep("array", 40)}))["d"]
    for _ in range(39):
        deep = deep[0]
    assert deep == [1]


def test_judge_accepts_the_contract_and_names_each_break():
    keys = {"params", "N", "analysis", "t_end"}
    ok2 = Outcome(2, "", "mechgen: in /tmp/x/fpu_chain.toml at key 'params.N': must be >= 1; expected 1.\n", 0.1)
    assert judge(ok2, "fpu_chain.toml", keys) == []
    ok1 = Outcome(1, "", "mechgen: ConvergenceError: Newton stalled after 50 iterations.\n", 0.1)
    assert judge(ok1, "fpu_chain.toml", keys) == []
    assert judge(Outcome(0, "done", "", 0.1), "fpu_chain.toml", keys) == []
    no_file = Outcome(2, "", "mechgen: at key 'params.N': bad.\n", 0.1)
    assert any("without the file" in p for p in judge(no_file, "fpu_chain.toml", keys))
    no_key = Outcome(2, "", "mechgen: in /tmp/fpu_chain.toml: something is wrong.\n", 0.1)
    assert any("without a key" in p for p in judge(no_key, "fpu_chain.toml", keys))
    raised = Outcome(None, "", "", 0.1, exc_type="ValueError", status="raised", mechgen_frame="mechgen/x.py:3 in f")
    assert judge(raised, "fpu_chain.toml", keys) == ["raised: ValueError:  (at mechgen/x.py:3 in f)"]
    assert judge(Outcome(None, "", "", 9, exc_type="CaseTimeout", status="timeout"), "f.toml", keys)
    unnamed = Outcome(1, "", "something broke\n", 0.1)
    assert any("named failure" in p for p in judge(unnamed, "fpu_chain.toml", keys))
    half = Outcome(2, "", ok2.err, 0.1, leftovers=[".tmp-abc.json"])
    assert any("half-written" in p for p in judge(half, "fpu_chain.toml", keys))
    assert names_a_key("at key '--set m': too large", set()) and not names_a_key("no key", {"N"})
    assert names_a_key("at key '\"" + "x" * 30 + "...\"': unknown", {"x" * 200})
    assert last_message("warning: x\nmechgen: in a: b.\n") == "mechgen: in a: b."


def test_a_case_past_its_limit_is_stopped_and_reported(tmp_path, warmed):
    """The limit works: a leapfrog of ~1e9 steps is cut at 2 s (a timeout, or a budget's exit 1/2 once there)."""
    doc = base_doc("fpu_chain")
    set_path(doc, ("analysis", 1, "t_end"), 1e8)
    outcome = run_case(Case("fpu_chain", doc, limit_s=2.0), tmp_path)
    assert outcome.seconds < 2.0 * (1 + COMPILE_EXTENSIONS) + KILL_GRACE + 1.0
    assert outcome.status in ("timeout", "killed") or outcome.code in (1, 2)
    assert CaseTimeout.__mro__[1] is BaseException  # no `except Exception` in mechgen swallows it


@pytest.mark.parametrize("scene", FAST_SCENES)
def test_each_fuzzed_scene_runs_unmutated(scene, warmed):
    """The bases the fuzzer mutates are themselves good: exit 0 with their JSON written."""
    outcome = warmed[scene]
    assert outcome.status == "returned" and outcome.code == 0, (outcome.exc_type, outcome.err[-500:])


# --- the explicit cases of issue 12 section 5 --------------------------------------------------------------------

def _edit(scene, edits=(), args=(), limit=EXPLICIT_LIMIT_S):
    doc = base_doc(scene)
    for path, value in edits:
        set_path(doc, path, value)
    return Case(scene, doc, mutations=[("set", path, value) for path, value in edits], args=list(args),
                limit_s=limit)


P = ("params",)
SWING = ("analysis", 2)  # spring_pendulum's simulate
CHAIN_RUN = ("analysis", 1)  # fpu_chain's simulate
# id: (case builder, accepted exit codes, key an exit-2 message must name (None: the file only),
#      xfail reason: the area whose fix it waits for, None where the case passes on this branch).
EXPLICIT = {
    "fpu_N_0": (lambda: _edit("fpu_chain", [(P + ("N",), 0)]), (2,), "N", None),
    # TOML reads `N = -0` as the integer 0 (the case above); -0.0 is the float
    "fpu_N_minus_0.0": (lambda: _edit("fpu_chain", [(P + ("N",), -0.0)]), (2,), "N", None),
    "fpu_N_minus_5": (lambda: _edit("fpu_chain", [(P + ("N",), -5)]), (2,), "N", None),
    "fpu_N_1e308": (lambda: _edit("fpu_chain", [(P + ("N",), 1e308)]), (2,), "N", None),
    "beam_N_0": (lambda: _edit("beam_modes", [(P + ("N",), 0)]), (2,), "N", None),
    "beam_N_minus_0.0": (lambda: _edit("beam_modes", [(P + ("N",), -0.0)]), (2,), "N", None),
    "beam_N_minus_5": (lambda: _edit("beam_modes", [(P + ("N",), -5)]), (2,), "N", None),
    "beam_N_1e308": (lambda: _edit("beam_modes", [(P + ("N",), 1e308)]), (2,), "N", None),
    "beam_quadrature_100000": (lambda: _edit("beam_modes", [(P + ("quadrature",), 100000)]), (1, 2),
                               "quadrature", None),
    "pendulum_samples_1e8": (lambda: _edit("spring_pendulum", [(SWING + ("samples",), 100_000_000),
                                                               (SWING + ("series",), True)]), (1, 2), "samples",
                             None),
    "laval_param_1e200_numpy": (lambda: _edit("laval_rotor", [(P + ("k_t",), 1e200), (("backend",), "numpy")]),
                                (0, 1), None, None),
    "laval_param_1e200_casadi": (lambda: _edit("laval_rotor", [(P + ("k_t",), 1e200), (("backend",), "casadi")]),
                                 (0, 1), None, None),
    "laval_param_1e200_c": (lambda: _edit("laval_rotor", [(P + ("k_t",), 1e200)]), (0, 1), None, None),
    # a length of 1e200 overflows the element matrices (L^3, L^4): not computable in doubles
    "beam_L_1e200_numpy": (lambda: _edit("beam_modes", [(P + ("L",), 1e200), (("backend",), "numpy")]), (1, 2),
                           None, None),
    "beam_L_1e200_casadi": (lambda: _edit("beam_modes", [(P + ("L",), 1e200), (("backend",), "casadi")]), (1, 2),
                            None, None),
    "beam_L_1e200_c": (lambda: _edit("beam_modes", [(P + ("L",), 1e200)]), (1, 2), None, None),
    # 1.8e308 is past the largest double: TOML reads it as inf
    "laval_k_r_1.8e308": (lambda: _edit("laval_rotor", [(P + ("k_r",), float("1.8e308"))]), (2,), "k_r", None),
    "pendulum_m_0": (lambda: _edit("spring_pendulum", [(P + ("m",), 0.0)]), (1, 2), "m", None),
    "pendulum_m_1e-300": (lambda: _edit("spring_pendulum", [(P + ("m",), 1e-300)]), (1, 2), "m", None),
    "pendulum_tolerances_1e-300": (lambda: _edit("spring_pendulum", [(SWING + ("rtol",), 1e-300),
                                                                     (SWING + ("atol",), 1e-300)]),
                                   (1, 2), "rtol", None),
    "pendulum_q0_1e300": (lambda: _edit("spring_pendulum", [(SWING + ("q0", "r"), 1e300)]), (1, 2), "q0",
                          None),
    "pendulum_stiff_RK45": (lambda: _edit("spring_pendulum", [(P + ("k",), 1e10), (SWING + ("method",), "RK45"),
                                                              (SWING + ("t_end",), 20.0)]), (1, 2), "t_end",
                            None),
    "balloon_beta_0": (lambda: _edit("balloon_stability", [(P + ("beta",), 0.0)], limit=60.0), (2,), "beta",
                       None),
    "beam_L_negative": (lambda: _edit("beam_modes", [(P + ("L",), -1.0)]), (2,), "L", None),
    "beam_rhoA_negative": (lambda: _edit("beam_modes", [(P + ("rhoA",), -1.0)]), (2,), "rhoA", None),
    "timoshenko_rhoI_5e-324": (lambda: _edit("timoshenko_modes", [(P + ("rhoI",), 5e-324)]), (2,), "rhoI",
                               None),
    "laval_array_500_deep": (lambda: _edit("laval_rotor", [(P + ("m",), Deep("array", 500))]), (2,), None,
                             None),
    "ross_part_kind_list": (lambda: _edit("ross_example_rotor", [(("parts", 0, "kind"), ["disk"])], limit=60.0),
                            (2,), "kind", None),
    # issue 33, the fuzz corpus of 500 (tests/fuzzing.py --examples 500 --seed 1 --limit 10): a disk's bore above
    # its outer diameter makes M singular; the message named only the internal key 'M' and the params, not the part
    # (now refused at load, at parts[1].inner, by the disk's declared check: Model.part's checks)
    "ross_disk_inner_999999": (lambda: _edit("ross_example_rotor", [(("parts", 0, "inner"), 999999)], limit=60.0),
                               (2,), "parts", None),
    # the same corpus re-run: 216 mode shapes of a 216-element beam at 3 sweep points tabulated the basis row by row
    # for every mode (12.7 s on a loaded machine, past the 10 s case limit); the rows are now tabulated once
    "beam_216_shapes": (lambda: _edit("beam_modes", [(P + ("N",), 216), (("analysis", 1, "analysis", "count"), 216)],
                                      limit=30.0), (0,), None, None),
    "laval_set_m_310_digits": (lambda: _edit("laval_rotor", args=["--set", "m=" + "1" * 310]), (2,), "m",
                               None),
    "laval_json_is_a_directory": (lambda: _edit("laval_rotor", args=["--json", "outdir"]), (2,), "--json",
                                  None),
    "laval_json_under_a_file": (lambda: _edit("laval_rotor", args=["--json", "afile/x.json"]), (2,), "--json",
                                None),
    "laval_plot_into_a_file": (lambda: _edit("laval_rotor", args=["--plot", "afile"]), (2,), "--plot", None),
    "fpu_t_end_1e9": (lambda: _edit("fpu_chain", [(CHAIN_RUN + ("t_end",), 1e9)]), (1, 2), "t_end", None),
    "fpu_leapfrog_2e9_steps": (lambda: _edit("fpu_chain", [(CHAIN_RUN + ("t_end",), 2000.0),
                                                           (CHAIN_RUN + ("dt",), 1e-6)]), (1, 2), "dt", None),
    # the default budget (max_seconds = 600) admits what this machine does in ten minutes (announced on
    # stderr, a bar on a terminal); a budget of 5 s shows the estimate from the first points refusing it
    "laval_sweep_999999_points": (lambda: _edit("laval_rotor", [(("analysis", 1, "over", "Omega", "num"), 999999),
                                                                (("analysis", 1, "max_seconds"), 5.0)]),
                                  (1,), "max_seconds", None),
}


def _params():
    for name, (_, _, _, reason) in EXPLICIT.items():
        marks = [pytest.mark.xfail(strict=False, reason=reason)] if reason else []
        yield pytest.param(name, id=name, marks=marks)


@pytest.mark.parametrize("name", list(_params()))
def test_explicit_case_ends_in_a_clear_word(name, tmp_path, warmed):
    build, accept, key, _ = EXPLICIT[name]
    case = build()
    (tmp_path / "outdir").mkdir()
    (tmp_path / "afile").write_text("a file, not a folder\n")
    outcome = run_case(case, tmp_path)
    problems = judge(outcome, f"{case.scene}.toml", keys_of(case.doc) | {key or "model"}, accept=accept,
                     key_required=key is not None)
    if not problems and outcome.code == 2 and key is not None:
        if not names_a_key(last_message(outcome.err), {key}):
            problems.append(f"exit 2 names another key than {key!r}: {last_message(outcome.err)[:300]}")
    assert not problems, f"{case.describe()}: {problems}\n{outcome.tb[-2000:]}"
    assert (tmp_path / "afile").read_text() == "a file, not a folder\n"
    assert not any((tmp_path / "outdir").iterdir())


# --- the fuzzer --------------------------------------------------------------------------------------------------

FUZZ_SETTINGS = dict(deadline=None, database=None, derandomize=True, print_blob=False,
                     phases=(Phase.explicit, Phase.generate),  # no shrinking: a failing case is reported as drawn
                     suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                            HealthCheck.data_too_large, HealthCheck.filter_too_much])


def _fuzz_once(case, tmp_path):
    workdir = Path(tempfile.mkdtemp(dir=tmp_path, prefix="case-"))
    outcome, problems = check_case(case, workdir)
    assert not problems, f"{case.scene}: {case.describe()}: {problems}\n{outcome.tb[-3000:]}"


@pytest.mark.xfail(FUZZ_XFAIL, reason=FUZZ_XFAIL_REASON, strict=False)
@settings(max_examples=CI_EXAMPLES, **FUZZ_SETTINGS)
@given(case=case_strategy(FAST_SCENES, limit_s=CI_LIMIT_S))
def test_fuzzed_scenes_end_in_a_clear_word(case, tmp_path, warmed):
    _fuzz_once(case, tmp_path)


SLOW_EXAMPLES = int(os.environ.get("MECHGEN_FUZZ_EXAMPLES", "0") or 0)


@pytest.mark.slow
@pytest.mark.skipif(SLOW_EXAMPLES <= 0, reason="opt-in: set MECHGEN_FUZZ_EXAMPLES (e.g. 3000) to run the large fuzz")
@pytest.mark.xfail(FUZZ_XFAIL, reason=FUZZ_XFAIL_REASON, strict=False)
@settings(max_examples=max(SLOW_EXAMPLES, 1), **FUZZ_SETTINGS)
@given(case=case_strategy(FAST_SCENES + ("beck_column", "stepped_rotor"),
                                                  limit_s=2 * CI_LIMIT_S))
def test_fuzzed_scenes_end_in_a_clear_word_large(case, tmp_path, warmed):
    _fuzz_once(case, tmp_path)
