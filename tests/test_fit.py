"""The ``fit`` analysis: least-squares estimates and their standard errors (mechgen.analyses.fit).

References, each independent of mechgen's solver:

* the limestone penetration data of Frew, Forrestal & Hanchak (2000), J. Appl. Mech. 67,
  "Penetration experiments with limestone targets and ogive-nose steel projectiles", eq. (3):
  R = K + k (2a0 / 2a), K = 607 MPa, k = 86 MPa, 2a0 = 25.4 mm; R = 913, 787, 693 MPa for
  2a = 7.1, 12.7, 25.4 mm. The model is linear in (K, k), so the estimate is the closed form of
  the normal equations A^T W A x = A^T W y (numpy), with C = s^2 (A^T W A)^-1,
  s^2 = sum w r^2 / (n - p) (e.g. Seber & Wild, Nonlinear Regression, 1989, sec. 2.1);
* noise-free data of a closed form y = A exp(-t / tau) + c (recovered exactly), and seeded
  Gaussian noise of known sigma: the linearised theory C = sigma^2 (J^T J)^-1 at the true
  parameters and the Monte-Carlo spread of the estimates over 50 seeds;
* the spring pendulum's spring frequency sqrt(k / m) (mechgen/models/spring_pendulum.py: small
  oscillations about r_eq = l0 + m g / k have frequencies sqrt(k/m) > sqrt(g / r_eq)).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.analyses.registry import get
from mechgen.cli import main
from mechgen.errors import SceneError

D = np.array([7.1, 12.7, 25.4])          # projectile diameter 2a, mm
R = np.array([913.0, 787.0, 693.0])      # target resistance, MPa
D0 = 25.4                                 # 2a0, mm
LIMESTONE = {"parameters": ["K", "k"], "start": {"K": 500.0, "k": 50.0}, "data": {"d": D.tolist(), "R": R.tolist()},
             "observed": "R", "expression": "K + k * (d0 / d)", "constants": {"d0": D0}}


@pytest.fixture(scope="module")
def pendulum():
    return mechgen.compile("spring_pendulum")


def _normal_equations(A: np.ndarray, y: np.ndarray, w: np.ndarray | None = None):
    """Weighted linear least squares by the normal equations: x, C = s^2 (A^T W A)^-1."""
    w = np.ones(len(y)) if w is None else w
    N = A.T @ (w[:, None] * A)
    x = np.linalg.solve(N, A.T @ (w * y))
    r = y - A @ x
    s2 = np.sum(w * r**2) / (len(y) - A.shape[1])
    return x, s2 * np.linalg.inv(N), r


def test_limestone_fit_is_the_linear_closed_form_and_brackets_the_paper(pendulum):
    fit = mechgen.fit(pendulum, **LIMESTONE)
    A = np.column_stack([np.ones(3), D0 / D])
    x, C, r = _normal_equations(A, R)
    assert [fit["K"], fit["k"]] == pytest.approx(x, rel=1e-10)
    assert [fit["K_stderr"], fit["k_stderr"]] == pytest.approx(np.sqrt(np.diag(C)), rel=1e-10)
    np.testing.assert_allclose(fit["covariance"], C, rtol=1e-9)
    np.testing.assert_allclose(fit["residuals"], r, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(np.array(fit["fitted"]) + fit["residuals"], R, rtol=1e-14)
    assert fit.outputs["observed"] == R.tolist() and fit["dof"] == 1 and fit["converged"] is True
    assert fit["rms"] == pytest.approx(np.sqrt(np.mean(r**2)), rel=1e-9)
    # the numbers worked by hand for the brief: K = 611.607 +- 9.278 MPa, k = 84.862 +- 3.809 MPa
    assert fit["K"] == pytest.approx(611.607, abs=5e-4) and fit["K_stderr"] == pytest.approx(9.278, abs=5e-4)
    assert fit["k"] == pytest.approx(84.862, abs=5e-4) and fit["k_stderr"] == pytest.approx(3.809, abs=5e-4)
    # the one-standard-error intervals contain the paper's K = 607 MPa, k = 86 MPa
    assert abs(fit["K"] - 607.0) < fit["K_stderr"] and abs(fit["k"] - 86.0) < fit["k_stderr"]
    # the same data in Pa and m: the estimates scale by 1e6 (the solver's scaling is the Jacobian's)
    si = mechgen.fit(pendulum, **{**LIMESTONE, "data": {"d": (D * 1e-3).tolist(), "R": (R * 1e6).tolist()},
                                  "constants": {"d0": D0 * 1e-3}, "start": {"K": 5e8, "k": 5e7}})
    assert [si["K"], si["k"]] == pytest.approx(x * 1e6, rel=1e-10)
    assert [si["K_stderr"], si["k_stderr"]] == pytest.approx(np.sqrt(np.diag(C)) * 1e6, rel=1e-10)


def test_sigma_weights_and_groups_are_the_weighted_closed_form_per_group(pendulum):
    rng = np.random.default_rng(7)
    x = np.tile(np.linspace(1.0, 4.0, 5), 2)
    group = np.repeat([3.0, 1.0], 5)     # first appearance: 3 then 1
    sigma = rng.uniform(0.5, 2.0, 10)
    y = np.where(group == 3.0, 2.0 + 0.5 * x, -1.0 + 1.5 * x) + rng.normal(0.0, 1.0, 10) * sigma
    fit = mechgen.fit(pendulum, parameters=["a", "b"], start={"a": 0.0, "b": 0.0}, observed="y", sigma="s",
                      group="g", expression="a + b * x", data={"x": x, "y": y, "s": sigma, "g": group})
    assert fit.outputs["groups"] == [3.0, 1.0] and fit.outputs["group_rows"] == [[1, 2, 3, 4, 5], [6, 7, 8, 9, 10]]
    assert fit.outputs["dof"] == [3, 3]
    for i, g in enumerate((3.0, 1.0)):
        rows = group == g
        ref, C, _ = _normal_equations(np.column_stack([np.ones(5), x[rows]]), y[rows], 1.0 / sigma[rows] ** 2)
        assert [fit["a"][i], fit["b"][i]] == pytest.approx(ref, rel=1e-10)
        assert [fit["a_stderr"][i], fit["b_stderr"][i]] == pytest.approx(np.sqrt(np.diag(C)), rel=1e-9)
        np.testing.assert_allclose(fit["covariance"][i], C, rtol=1e-8)


def test_as_many_rows_as_parameters_reports_null_standard_errors(pendulum):
    fit = mechgen.fit(pendulum, **{**LIMESTONE, "data": {"d": D[:2].tolist(), "R": R[:2].tolist()}})
    # two rows, two parameters: the line through both points, K + k d0/d = R exactly
    k = (R[0] - R[1]) / (D0 / D[0] - D0 / D[1])
    assert fit["k"] == pytest.approx(k, rel=1e-10) and fit["K"] == pytest.approx(R[1] - k * D0 / D[1], rel=1e-10)
    assert fit["K_stderr"] is None and fit["k_stderr"] is None and fit["covariance"] is None and fit["dof"] == 0
    assert any("no degree of freedom" in line for line in get("fit").summary(fit.outputs))


def test_parameters_the_data_cannot_separate_get_null_standard_errors(pendulum):
    # y = a b x determines only the product a b (here 3): J's columns b x and a x are parallel
    x = np.array([1.0, 2.0, 3.0, 4.0])
    fit = mechgen.fit(pendulum, parameters=["a", "b"], start={"a": 1.0, "b": 2.0}, data={"x": x, "y": 3.0 * x},
                      observed="y", expression="a * b * x")
    assert fit["a"] * fit["b"] == pytest.approx(3.0, rel=1e-9)
    assert fit["a_stderr"] is None and fit["covariance"] is None and fit["dof"] == 2
    assert any("do not determine" in line for line in get("fit").summary(fit.outputs))


T = np.linspace(0.0, 4.0, 40)
DECAY = {"parameters": ["A", "tau", "c"], "start": {"A": 1.0, "tau": 3.0, "c": 0.0}, "observed": "y",
         "expression": "A * exp(-t / tau) + c"}


def test_noise_free_decay_is_recovered_exactly(pendulum):
    y = 2.5 * np.exp(-T / 0.8) + 0.3
    fit = mechgen.fit(pendulum, **DECAY, data={"t": T, "y": y})
    assert [fit["A"], fit["tau"], fit["c"]] == pytest.approx([2.5, 0.8, 0.3], rel=1e-9)
    assert max(fit["A_stderr"], fit["tau_stderr"], fit["c_stderr"]) < 1e-9
    assert fit["rms"] < 1e-12 and fit["converged"]


def test_a_trial_step_outside_the_domain_is_shortened_and_a_bad_start_is_refused(pendulum):
    # y = 2 sqrt(x - 0.99): Gauss-Newton steps from these starts overshoot a past min(x) = 1, where
    # sqrt is undefined; the trust region shrinks instead and the closed form's a, b come back
    x = np.array([1.0, 1.5, 2.0, 3.0, 4.0, 6.0])
    data = {"x": x, "y": 2.0 * np.sqrt(x - 0.99)}
    for start in ({"a": 0.0, "b": 1.0}, {"a": -5.0, "b": 0.2}, {"a": 0.5, "b": 10.0}):
        fit = mechgen.fit(pendulum, parameters=["a", "b"], start=start, data=data, observed="y",
                          expression="b * sqrt(x - a)")
        assert [fit["a"], fit["b"]] == pytest.approx([0.99, 2.0], rel=1e-9)
    with pytest.raises(SceneError, match=r"fit.expression.*not finite.*data row 1 \(parameters a = 2, b = 1\)"):
        mechgen.fit(pendulum, parameters=["a", "b"], start={"a": 2.0, "b": 1.0}, data=data, observed="y",
                    expression="b * sqrt(x - a)")


def test_noisy_decay_standard_errors_match_theory_and_monte_carlo(pendulum):
    true, sigma = np.array([2.5, 0.8, 0.3]), 0.02
    clean = true[0] * np.exp(-T / true[1]) + true[2]
    # linearised theory: C = sigma^2 (J^T J)^-1, J the model's derivatives at the true parameters
    J = np.column_stack([np.exp(-T / true[1]), true[0] * T / true[1] ** 2 * np.exp(-T / true[1]), np.ones_like(T)])
    theory = sigma * np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    estimates, errors = [], []
    for seed in range(50):
        y = clean + np.random.default_rng(seed).normal(0.0, sigma, T.size)
        fit = mechgen.fit(pendulum, **DECAY, data={"t": T, "y": y})
        estimates.append([fit["A"], fit["tau"], fit["c"]])
        errors.append([fit["A_stderr"], fit["tau_stderr"], fit["c_stderr"]])
    estimates, errors = np.array(estimates), np.array(errors)
    assert (np.abs(estimates[0] - true) < 3 * errors[0]).all()                      # seed 0
    assert (np.abs(estimates - true) < 3 * errors).sum() >= 0.95 * estimates.size    # 99.7 % expected
    spread = estimates.std(axis=0, ddof=1)
    np.testing.assert_allclose(errors.mean(axis=0), spread, rtol=0.3)
    np.testing.assert_allclose(errors.mean(axis=0), theory, rtol=0.1)


def test_spring_constant_from_modes_of_several_masses(pendulum):
    m = np.array([0.5, 1.0, 2.0, 4.0])
    omega = np.sqrt(40.0 / m)       # the spring mode, the higher of the two (module docstring)
    fit = mechgen.fit(pendulum, parameters=["k"], start={"k": 25.0}, data={"m": m, "omega": omega},
                      observed="omega", inputs=["m"], analysis={"kind": "modes", "at": {"r": 1.5}},
                      output="frequencies[2]")
    assert fit["k"] == pytest.approx(40.0, rel=1e-10)
    assert fit["k_stderr"] < 1e-10 and fit["converged"] and fit["evaluations"] < 100
    assert fit["x_column"] == "m" and fit.outputs["x_values"] == m.tolist()
    assert mechgen.modes(pendulum, at={"r": 1.5})["frequencies"][1] == pytest.approx(np.sqrt(40.0), rel=1e-12)
    with pytest.raises(SceneError, match="frequencies"):   # a list output needs its index
        mechgen.fit(pendulum, parameters=["k"], data={"m": m, "omega": omega}, observed="omega", inputs=["m"],
                    analysis={"kind": "modes", "at": {"r": 1.5}}, output="frequencies")


def test_the_evaluation_budget_ends_the_fit_naming_the_key(pendulum):
    from mechgen.runtime.core.budget import BudgetExceeded

    with pytest.raises(BudgetExceeded, match=r"fit 'fit': fit of K, k: stopped after 1 evaluations.*max_evaluations"):
        mechgen.fit(pendulum, **LIMESTONE, max_evaluations=1)


# --------------------------------------------------------------------------- scene files

CSV = """# Frew, Forrestal & Hanchak (2002): 2a in mm, R in MPa
d,R
7.1, 913
12.7,787

25.4,693
"""
SCENE = """model = "spring_pendulum"
[[analysis]]
name = "limestone"
kind = "fit"
parameters = ["K", "k"]
start = { K = 500.0, k = 50.0 }
data = "data/limestone.csv"
observed = "R"
expression = "K + k * (d0 / d)"
constants = { d0 = 25.4 }
"""
SPRING = """[[analysis]]
name = "spring"
kind = "fit"
parameters = ["k"]
data = { m = [0.5, 1.0, 2.0], w = [8.94427190999916, 6.324555320336759, 4.47213595499958] }
observed = "w"
inputs = ["m"]
analysis = { kind = "modes", at = { r = 1.5 } }
output = "frequencies[2]"
"""


def _scene(tmp_path, text: str, csv: str = CSV) -> str:
    (tmp_path / "data").mkdir(exist_ok=True)
    (tmp_path / "data" / "limestone.csv").write_text(csv)
    path = tmp_path / "fit.toml"
    path.write_text(text)
    return str(path)


def _cli(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_scene_with_a_csv_file_runs_from_the_command_line(tmp_path, capsys):
    target = tmp_path / "out.json"
    code, out, err = _cli(["run", _scene(tmp_path, SCENE + SPRING), "--json", str(target)], capsys)
    assert code == 0, err
    lime, spring = json.loads(target.read_text())["analyses"]
    outputs = lime["outputs"]
    assert {"K", "K_stderr", "k", "k_stderr", "residuals", "fitted", "observed", "rms", "dof", "covariance",
            "converged", "evaluations"} <= set(outputs)
    x, C, _ = _normal_equations(np.column_stack([np.ones(3), D0 / D]), R)
    assert [outputs["K"], outputs["k"]] == pytest.approx(x, rel=1e-10)
    assert [outputs["K_stderr"], outputs["k_stderr"]] == pytest.approx(np.sqrt(np.diag(C)), rel=1e-10)
    assert spring["outputs"]["k"] == pytest.approx(40.0, rel=1e-10)   # the spring frequencies sqrt(40 / m)
    assert "K: 611.607 +- 9.27798" in out


def test_a_scene_that_needs_no_kernels_is_cached_like_any_other(tmp_path, monkeypatch):
    """An expression fit compiles a request for no kernels; its cache entry is valid on the next run
    (it was once refused as damaged, 'no kernel specs', warned about and rebuilt every run)."""
    import warnings

    from mechgen.scene.run import system_for

    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "cache"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, first = system_for("spring_pendulum", (), (), None, (), "numpy", fresh=True)
        _, second = system_for("spring_pendulum", (), (), None, (), "numpy", fresh=True)
    assert first.kernels == second.kernels == {} and second.cached


def test_scene_plots_data_and_residuals(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    code, out, err = _cli(["run", _scene(tmp_path, SCENE), "--plot", str(tmp_path / "plots")], capsys)
    assert code == 0, err
    assert (tmp_path / "plots" / "fit_limestone.png").stat().st_size > 1000


BAD = {
    "parameters_not_a_list": (SCENE.replace('["K", "k"]', '"K"'), "parameters", "array"),
    "unknown_parameter": (SCENE.replace('["K", "k"]', '["K", "k", "z"]'), "parameters[3]", "does not appear"),
    "unknown_model_parameter": (SCENE.replace("name = \"limestone\"", "name = \"x\"").split("[[analysis]]")[0]
                                + SPRING.replace('["k"]', '["kk"]'), "parameters[1]", "no parameter"),
    "size_parameter": ('model = "fpu_chain"\n' + SPRING.replace('["k"]', '["N"]'), "parameters[1]", "a size"),
    "expression_unknown_name": (SCENE.replace("(d0 / d)", "(d0 / dd)"), "expression", "unknown name 'dd'"),
    "expression_syntax": (SCENE.replace("(d0 / d)", "d.real"), "expression", "attribute"),
    "expression_injection": (SCENE.replace("K + k * (d0 / d)", "__import__('os').system('echo pwned')"),
                             "expression", "not allowed"),
    "observed_missing": (SCENE.replace('observed = "R"', 'observed = "Q"'), "observed", "no data column 'Q'"),
    "ragged_columns": (SCENE.replace('"data/limestone.csv"', "{ d = [7.1, 12.7, 25.4], R = [913, 787] }"),
                       "data.R", "2 values"),
    "fewer_rows_than_parameters": (SCENE.replace('"data/limestone.csv"', "{ d = [7.1], R = [913] }"), "data",
                                   "fewer than the 2 parameters"),
    "both_models": (SCENE + 'analysis = { kind = "modes" }\noutput = "rms"\n', "analysis", "both"),
    "neither_model": (SCENE.replace('expression = "K + k * (d0 / d)"\n', ""), "expression", "neither"),
    # K is not a spring_pendulum parameter (k is: its start would default to the scene's k)
    "no_start": (SCENE.replace("start = { K = 500.0, k = 50.0 }", "start = { k = 50.0 }"), "start.K",
                 "no starting value"),
    "start_not_a_parameter": (SCENE.replace("k = 50.0 }", "k = 50.0, q = 1 }"), "start.q", "not a parameter"),
    "sigma_not_positive": (SCENE.replace('"data/limestone.csv"', "{ d = [7.1, 12.7, 25.4], R = [913, 787, 693], "
                                         "s = [1, 0, 1] }") + 'sigma = "s"\n', "sigma", "sigma = 0.0"),
    "group_too_small": (SCENE.replace('"data/limestone.csv"', "{ d = [7.1, 12.7, 25.4], R = [913, 787, 693], "
                                      "g = [1, 1, 2] }") + 'group = "g"\n', "group", "group g = 2 has 1 row,"),
    "input_out_of_bounds": (SCENE.split("[[analysis]]")[0] + SPRING.replace("m = [0.5,", "m = [-0.5,"),
                            "inputs[1]", "row 1, column 'm'"),
    "constants_with_analysis": (SCENE.split("[[analysis]]")[0] + SPRING + "constants = { a = 1 }\n", "constants",
                                "applies to an expression fit"),
    "too_many_rows": (SCENE + "[limits]\nrows = 2\n", "data", "more than 2 rows"),
}
BAD_CSV = {
    "missing_file": ("", "data", "not found"),
    "not_a_number": (CSV.replace("787", "78x7"), "data", "line 4 of data/limestone.csv, column 'R': '78x7'"),
    "ragged_row": (CSV.replace("12.7,787", "12.7,787,5"), "data", "line 4 of data/limestone.csv has 3 cells"),
    "bad_header": (CSV.replace("d,R", "d mm,R"), "data", "not an identifier"),
    "no_rows": ("d,R\n", "data", "no data rows"),
    "not_finite": (CSV.replace("913", "nan"), "data", "not a finite number"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_fit_scene_exits_2_naming_the_key(case, tmp_path, capsys):
    text, key, words = BAD[case]
    code, out, err = _cli(["run", _scene(tmp_path, text)], capsys)
    assert code == 2, err
    assert "fit.toml" in err and f"analysis[1].{key}'" in err and words in err, err
    assert "Traceback" not in err and "pwned" not in out and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("case", sorted(BAD_CSV))
def test_bad_data_file_exits_2_naming_the_file_and_line(case, tmp_path, capsys):
    csv, key, words = BAD_CSV[case]
    path = _scene(tmp_path, SCENE, csv)
    if case == "missing_file":
        (tmp_path / "data" / "limestone.csv").unlink()
    code, out, err = _cli(["run", path], capsys)
    assert code == 2, err
    assert "fit.toml" in err and f"analysis[1].{key}'" in err and words in err, err
