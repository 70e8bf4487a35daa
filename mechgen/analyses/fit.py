"""``fit``: least-squares estimates of parameters from data (scipy.optimize.least_squares, method trf).

Minimises S(theta) = sum_i ((y_i - f_i(theta)) / sigma_i)^2 over the rows i of ``data``, y the
``observed`` column, sigma the optional ``sigma`` column (standard deviations; 1 without it), and
reports one standard error per parameter, sqrt(diag C), from

    C = s^2 (J^T J)^-1,   s^2 = S(theta*) / (n - p),   J_ij = d((y_i - f_i) / sigma_i) / d theta_j

at the estimate theta* (n rows, p parameters): sigma weights the rows relative to each other and
the error scale s^2 comes from the residuals (scipy's curve_fit with absolute_sigma=False). With
n = p there is no degree of freedom left: the standard errors and C are null. A J of numerical
rank < p (a parameter the data cannot determine) also gives null.

The model f, one of:

* ``expression``: a formula of data columns, ``constants`` (a table of numbers) and the
  parameters, parsed by the whitelist parser (mechgen.scene.expr; every name must be one of
  those), e.g. ``"K + k * (d0 / d)"``; J is exact (mechgen.scene.expr_arrays). The scene's
  kernels are not used. A parameter that is not one of the model's needs a ``start`` value.
* ``analysis``: an inner analysis table as a sweep's (``{kind = "modes", at = {...}}``: modes,
  stability, steady or simulate) with ``output`` (its number output, or ``name[i]``: entry i,
  1-based, of a list output) and ``inputs`` (data columns that set model parameters per row).
  The parameters are numeric model parameters, kept free in the kernels with the inputs; each
  evaluation runs the inner analysis once per row. J is by finite differences (``jacobian``:
  "3-point" (default) or "2-point", relative step ``diff_step``, default 1e-6): with an inner
  analysis accurate to a relative delta, J is accurate to about delta / diff_step (2-point:
  plus diff_step), and the estimate to no better than delta times the problem's condition; raise
  diff_step (about sqrt(delta) for 2-point, delta^(1/3) for 3-point) for an integrator's rtol. The
  parameters stay within their declared bounds (positive, minimum, maximum, below).

``parameters`` (names, required), ``start`` (name = value; default the scene's value), ``group``
(a column: the parameters are estimated separately for the rows of each distinct value, in
first-appearance order), ``tol`` (least_squares' ftol = xtol = gtol, default 1e-10),
``max_seconds`` (wall time, default 600) and ``max_evaluations`` (evaluations of the model on
all rows of a group, the Jacobian's included; default none). Data: mechgen.analyses.fit_data.

Outputs: per parameter ``p`` and ``p_stderr`` (a list per group when grouped); ``residuals``
(y - f), ``fitted``, ``observed`` (row order); ``rms`` (of the residuals, all rows); ``dof``
(n - p; per group); ``covariance`` (C; per group); ``groups`` and ``group_rows`` (1-based rows)
when grouped; ``converged``, ``message`` (least_squares' status), ``evaluations``; ``x_column``
and ``x_values`` (the first input or column of the expression, for the plot).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from mechgen.analyses import fit_data, summary
from mechgen.analyses.fit_check import check, frees, needs, SCHEMA
from mechgen.analyses.fit_model import AnalysisModel, ExpressionModel
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget


class _Cached:
    """The model at the latest parameters asked for (least_squares asks for f, then J, at the same point).

    An expression outside its domain (sqrt of a negative number ...) at a trial point after the start
    gives NaN residuals, on which least_squares (trf) shrinks its trust region and tries a shorter step;
    at the start it is the scene's error.
    """

    def __init__(self, model, rows: np.ndarray, budget: Budget) -> None:
        self.model, self.rows, self.budget = model, rows, budget
        self.theta, self.value = None, None

    def __call__(self, theta: np.ndarray):
        if self.theta is None or not np.array_equal(theta, self.theta):
            self.budget.spend(1, lambda: f"{self.budget.used - 1} evaluations")
            try:
                value = self.model.predict(theta, self.rows)
            except SceneError:
                if self.theta is None or not self.model.exact:
                    raise
                value = (np.full(len(self.rows), np.nan), None)
            self.value, self.theta = value, np.array(theta)
        return self.value


def _covariance(jac: np.ndarray, ssr: float) -> np.ndarray | None:
    """s^2 (J^T J)^-1 with s^2 = SSR / (n - p), by the SVD of J; None when n = p or J is rank-deficient."""
    n, p = jac.shape
    if n <= p:
        return None
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    if not sv[0] > 0 or sv[-1] <= np.finfo(float).eps * max(n, p) * sv[0]:
        return None
    return (vt.T / sv**2) @ vt * (ssr / (n - p))


def _solve(model, rows: np.ndarray, y: np.ndarray, sigma: np.ndarray, options: dict, budget: Budget) -> dict:
    """One group's estimate: theta*, C, the fitted values, whether least_squares converged."""
    from scipy.optimize import least_squares  # here: a scene without a fit never imports scipy.optimize

    cached = _Cached(model, rows, budget)
    w = 1.0 / sigma[rows]

    def residual(theta):
        return (y[rows] - cached(theta)[0]) * w

    def exact(theta):
        return -cached(theta)[1] * w[:, None]

    lb, ub = options["_bounds"]
    tol = options["tol"]
    # solve for u = theta / scale (scale: |start|, or 1 for a start at 0): least_squares' gtol compares a gradient
    # with bounds scaling (trf, Coleman-Li) that keeps the parameters' units; R ~ 1e9 Pa would stop it at once
    start = np.asarray(options["_start"], dtype=float)
    scale = np.where(start != 0, np.abs(start), 1.0)
    res = least_squares(lambda u: residual(u * scale), start / scale,
                        jac=(lambda u: exact(u * scale) * scale) if model.exact else options["jacobian"],
                        bounds=(np.asarray(lb) / scale, np.asarray(ub) / scale), method="trf", x_scale="jac",
                        ftol=tol, xtol=tol, gtol=tol, diff_step=None if model.exact else options["diff_step"])
    x = res.x * scale
    jac = exact(x) if model.exact else res.jac / scale
    fitted = cached(x)[0] if model.exact else y[rows] - res.fun / w
    cov = _covariance(np.asarray(jac, dtype=float), float(np.sum(res.fun**2)))
    return {"x": x, "cov": cov, "fitted": fitted, "converged": bool(res.success), "message": res.message,
            "dof": len(rows) - len(x)}


def run_fit(system, options: dict, context: dict) -> dict:
    """The estimate of each group (all rows without ``group``), collected in row order."""
    data, names = options["data"], options["parameters"]
    y = data.columns[options["observed"]]
    sigma = data.columns[options["sigma"]] if "sigma" in options else np.ones(data.rows)
    budget = Budget(f"fit of {', '.join(names)}", limit=options.get("max_evaluations"), key="max_evaluations",
                    unit="evaluations", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    if "expression" in options:
        model = ExpressionModel(options["expression"], data, options.get("constants", {}), names)
    else:
        model = AnalysisModel(system, context, options["analysis"], options["output"], options.get("inputs", []),
                              data, names, f"{options['_key']}.output", budget)
    grouped = "group" in options
    parts = fit_data.groups(data.columns[options["group"]] if grouped else None, data.rows)
    fits = [_solve(model, rows, y, sigma, options, budget) for _, rows in parts]
    return collect(options, parts, fits, y, budget.used)


def collect(options: dict, parts: list, fits: list[dict], y: np.ndarray, evaluations: int) -> dict:
    """The outputs (module docstring) from each group's estimate."""
    grouped = "group" in options
    one = (lambda values: values) if grouped else (lambda values: values[0])
    out: dict = {}
    for j, name in enumerate(options["parameters"]):
        out[name] = one([float(f["x"][j]) for f in fits])
        out[f"{name}_stderr"] = one([None if f["cov"] is None else float(np.sqrt(f["cov"][j, j])) for f in fits])
    fitted = np.empty_like(y)
    for (_, rows), f in zip(parts, fits):
        fitted[rows] = f["fitted"]
    residuals = y - fitted
    out.update(residuals=residuals.tolist(), fitted=fitted.tolist(), observed=y.tolist(),
               rms=float(np.sqrt(np.mean(residuals**2))), dof=one([f["dof"] for f in fits]),
               covariance=one([None if f["cov"] is None else f["cov"].tolist() for f in fits]))
    if grouped:
        out["groups"] = [v for v, _ in parts]
        out["group_rows"] = [(rows + 1).tolist() for _, rows in parts]
    out["converged"] = all(f["converged"] for f in fits)
    out["message"] = "; ".join(dict.fromkeys(f["message"] for f in fits))
    out["evaluations"] = int(evaluations)
    column = options["_x_column"]
    out["x_column"] = column or "row"
    out["x_values"] = (options["data"].columns[column] if column else np.arange(1.0, len(y) + 1)).tolist()
    return out


def summary_lines(outputs: dict) -> list[str]:
    """Each parameter with its standard error, then rows, dof, rms, evaluations and convergence."""
    params = [k[: -len("_stderr")] for k in outputs if k.endswith("_stderr") and k[: -len("_stderr")] in outputs]
    lines = []
    if "groups" in outputs:
        lines.append(f"    groups: {summary.fmt(outputs['groups'])}")
    for name in params:
        err = outputs[f"{name}_stderr"]
        lines.append(f"    {name}: {summary.fmt(outputs[name])} +- {summary.fmt(err)} (one standard error)")
    dof = outputs["dof"]
    lines.append(f"    rows: {len(outputs['observed'])}, dof: {summary.fmt(dof)}, rms: {summary.fmt(outputs['rms'])}, "
                 f"evaluations: {outputs['evaluations']}, converged: {outputs['converged']}")
    if 0 in (dof if isinstance(dof, list) else [dof]):
        lines.append("    no degree of freedom left (rows = parameters): standard errors not estimated (null)")
    elif any(c is None for c in (outputs["covariance"] if isinstance(dof, list) else [outputs["covariance"]])):
        lines.append("    the data do not determine every parameter (J^T J singular): standard errors null")
    if not outputs["converged"]:
        lines.append(f"    not converged: {outputs['message']}")
    return lines


def plot(plt, a: dict, path: Path) -> list[Path]:
    """The observed values (points) and the fitted ones (line) against the first input or expression column,
    one series per group; the residuals below."""
    out = a["outputs"]
    x, y, f, r = (np.asarray(out[k], dtype=float) for k in ("x_values", "observed", "fitted", "residuals"))
    rows = [np.asarray(g) - 1 for g in out["group_rows"]] if "group_rows" in out else [np.arange(len(x))]
    labels = [f"group {summary.fmt(g)}" for g in out["groups"]] if "groups" in out else ["data"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6, 6), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    for idx, label, colour in zip(rows, labels, plt.rcParams["axes.prop_cycle"].by_key()["color"] * len(rows)):
        order = idx[np.argsort(x[idx], kind="stable")]
        top.plot(x[order], y[order], "o", color=colour, ms=4, label=f"{label}: observed")
        top.plot(x[order], f[order], "-", color=colour, lw=1, label=f"{label}: fitted")
        bottom.plot(x[order], r[order], "o-", color=colour, ms=3, lw=0.5)
    bottom.axhline(0.0, color="0.6", lw=0.5)
    top.set_ylabel("observed, fitted")
    top.legend(fontsize=7)
    top.set_title(f"{a['name']}: rms residual {out['rms']:.4g}", fontsize=9)
    bottom.set_ylabel("residual")
    bottom.set_xlabel(out["x_column"])
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("fit", SCHEMA, run_fit, needs, summary_lines, check=check, frees=frees, plot=plot))
