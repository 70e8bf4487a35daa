"""``cross_section``: a rod section's stiffness matrix K at the system's parameter values.

The model declares its section with ``@model.section_stiffness`` (a 6 x 6 K(p), e.g. from
mechgen.symbolic.cross_section.cross_section_stiffness: K = int_A D^T C D dA from Lame lam, mu, the
section's geometry and the reference curvature and torsion); the ``section`` kernel evaluates it.
No scene keys. Outputs: ``K`` (6 x 6 nested list ordered [K_uu, K_uw; K_wu, K_ww]: N, N m, N m^2) and
``eigenvalues`` (ascending). A K that is not finite or not symmetric positive definite (a section
reaching the centre of curvature, a negative shear modulus ...) is bad input: an InputError naming
the parameters (exit 2).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import summary
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.errors import InputError

#: the strain names of the twist order (v, w): extension, shears; twist, bendings
STRAINS = ("u1", "u2", "u3", "w1", "w2", "w3")


def needs(options: dict, *, internal: bool) -> set[str]:
    """The section kernel only."""
    return {"section"}


def _values(system) -> str:
    """The free parameter values and the names folded into the kernels, for messages."""
    free = ", ".join(f"{k} = {float(v):g}" for k, v in zip(system.metadata.params, system.params))
    folded = ", ".join(system.folded) or ", ".join(getattr(system, "fixed", {}))
    text = " and ".join(x for x in (free, f"the values of {folded} folded into the kernels" if folded else "") if x)
    return text or "the scene's parameter values"


def checked_stiffness(system) -> np.ndarray:
    """K (6 x 6) of the system's section: finite, symmetric to round-off and positive definite, else an
    InputError naming the parameters (key ``params``)."""
    model = system.metadata.model
    if "section" not in system.kernels:
        raise InputError(f"model {model} declares no cross-section (the cross_section analysis needs one)",
                         key="kind", expected="a model with @model.section_stiffness, or another analysis kind")
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):  # a bad section is reported below
        K = np.asarray(system.call("section", check=False)["K"], dtype=float).reshape(6, 6)
    if not np.all(np.isfinite(K)):
        bad = [f"K[{STRAINS[i]},{STRAINS[j]}]" for i, j in zip(*np.nonzero(~np.isfinite(K)))]
        raise InputError(f"the section stiffness of model {model} is not finite ({', '.join(bad[:4])}) at "
                         f"{_values(system)}: the section may reach the centre of curvature", key="params",
                         expected="parameters of a section with a finite stiffness (kappa0 b < 2 for the arc)")
    scale = float(np.max(np.abs(K))) or 1.0
    if np.max(np.abs(K - K.T)) > 1e-12 * scale:
        raise InputError(f"the section stiffness of model {model} is not symmetric at {_values(system)}",
                         key="params", expected="a section stiffness derived from a strain energy")
    eig, vec = np.linalg.eigh(K)
    if eig[0] <= 1e-14 * max(abs(eig[-1]), 1e-300):
        along = STRAINS[int(np.argmax(np.abs(vec[:, 0])))]
        raise InputError(f"the section stiffness of model {model} is not positive definite at {_values(system)}: "
                         f"smallest eigenvalue {eig[0]:.6g} (mostly along {along})", key="params",
                         expected="parameters of a stable section (mu > 0, 3 lam + 2 mu > 0, the section short of "
                                  "the centre of curvature)")
    return K


def run_cross_section(system, options: dict, context: dict) -> dict:
    """K and its eigenvalues (ascending)."""
    K = checked_stiffness(system)
    return {"K": [[float(x) + 0.0 for x in row] for row in K], "eigenvalues": [float(x) for x in np.linalg.eigvalsh(K)]}


def lines(outputs: dict) -> list[str]:
    """K row by row (6 significant digits), then its eigenvalues."""
    rows = [f"    K[{STRAINS[i]}]: " + "  ".join(f"{x: .6g}" for x in row) for i, row in enumerate(outputs["K"])]
    return ["    K = [K_uu, K_uw; K_wu, K_ww] (N, N m, N m^2):"] + rows + summary.output_lines(outputs, skip=("K",))


register(AnalysisKind("cross_section", {}, run_cross_section, needs, lines, sweepable=True))
