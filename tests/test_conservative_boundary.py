"""stability_boundary where the growth rate is exactly zero on the stable side (issue 25, item 8).

An undamped column's eigenvalues are s = +-i w on the stable side (max Re s = 0 exactly), so the growth rate
cannot bracket the boundary; the analysis bisects on the stability verdict instead (an eigenvalue through zero:
divergence; two frequencies merging: flutter). References:

* Euler's load of a pinned-pinned column, P_E = pi^2 EI / L^2 (Timoshenko & Gere, "Theory of Elastic
  Stability", 2nd ed., 1961, sect. 2.1): divergence.
* a mass in a rotating anisotropic well (springs k1 < k2 turning at Omega; rotating coordinates x, y):
  x'' - 2 Omega y' + (k1 - Omega^2) x = 0, y'' + 2 Omega x' + (k2 - Omega^2) y = 0, whose characteristic
  polynomial s^4 + (k1 + k2 + 2 Omega^2) s^2 + (k1 - Omega^2)(k2 - Omega^2) = 0 has a real positive root exactly
  for sqrt(k1) < Omega < sqrt(k2): divergence at Omega = sqrt(k1), gyroscopic restabilisation at sqrt(k2)
  (Ziegler 1968, sect. 3.4; Meirovitch, "Methods of Analytical Dynamics", 1970, sect. 6.11): a conservative
  gyroscopic system, stable with all Re s = 0 on both sides.
* Beck's column, a cantilever under a follower (tangential) tip load: flutter at P_cr = 20.05 EI / L^2, where
  its two lowest frequencies merge (Beck, Z. angew. Math. Phys. 3, 1952; Ziegler, "Principles of Structural
  Stability", 1968, sect. 4.3).
"""
import numpy as np
import pytest

import mechgen
from mechgen.errors import ConvergenceError, InputError

COLUMN = '''"""A pinned-pinned column under a dead axial load P: V = EI/2 w_ss^2 - P/2 w_s^2."""
from mechgen import Model, Param, fix

model = Model("pinned_column", doc=__doc__)
model.params(Param("EI", 2.0), Param("rhoA", 1.0), Param("L", 1.5), Param("P", 0.0))
model.field("w", length="L", discretisation="hermite", N=16)
model.kinetic_density(lambda u, p: p.rhoA / 2 * u.w_t**2)
model.potential_density(lambda u, p: p.EI / 2 * u.w_ss**2 - p.P / 2 * u.w_s**2)
model.boundary(lambda: [fix("w", "start"), fix("w", "end")])
'''


WELL = '''"""A unit mass in a rotating anisotropic well: T = ((x' - Omega y)^2 + (y' + Omega x)^2) / 2."""
from mechgen import Model, Param

model = Model("rotating_well", doc=__doc__)
model.params(Param("k1", 4.0), Param("k2", 9.0), Param("Omega", 0.0))
model.coordinates("x", "y")
model.kinetic(lambda q, v, p: ((v.x - p.Omega * q.y)**2 + (v.y + p.Omega * q.x)**2) / 2)
model.potential(lambda q, p: (p.k1 * q.x**2 + p.k2 * q.y**2) / 2)
'''


@pytest.fixture(scope="module")
def column(tmp_path_factory):
    path = tmp_path_factory.mktemp("column") / "pinned_column.py"
    path.write_text(COLUMN)
    return str(path)


def test_euler_load_of_a_pinned_column(column):
    """P_c against pi^2 EI / L^2 = 8.7730: 5e-6 relative (16 cubic Hermite elements; the buckling load's
    discretisation error falls as h^4: measured 2.06e-6 here, 3.28e-5 at 8 elements); a real crossing."""
    EI, L = 2.0, 1.5
    res = mechgen.stability_boundary(mechgen.compile(column, backend="numpy"), parameter="P", bracket=[5.0, 15.0])
    euler = np.pi**2 * EI / L**2
    assert res["P_critical"] == pytest.approx(euler, rel=5e-6)
    assert res["crossing"] == "real" and res["frequency_critical"] == 0.0
    assert res["method"] == "bisection" and res["verdict"] == "stable"
    coarse = mechgen.stability_boundary(mechgen.compile(column, {"N": 8}, backend="numpy"), parameter="P",
                                        bracket=[5.0, 15.0])
    ratio = (coarse["P_critical"] - euler) / (res["P_critical"] - euler)
    assert 12.0 < ratio < 20.0  # h^4 convergence: halving h divides the error by about 16 (measured 15.9)


def test_rotating_well_divergence_and_gyroscopic_restabilisation(tmp_path):
    """Omega_c = sqrt(k1) = 2 (divergence: an eigenvalue through zero) and sqrt(k2) = 3 (the pair returns to
    the imaginary axis), to 1e-9 (bisection to rtol 1e-12; the verdict flips where the constant term
    (k1 - Omega^2)(k2 - Omega^2), computed to round-off, changes sign)."""
    path = tmp_path / "well.py"
    path.write_text(WELL)
    system = mechgen.compile(str(path), backend="numpy")
    onset = mechgen.stability_boundary(system, parameter="Omega", bracket=[1.0, 2.5])
    assert onset["Omega_critical"] == pytest.approx(2.0, rel=1e-9)
    assert onset["crossing"] == "real" and onset["method"] == "bisection"
    back = mechgen.stability_boundary(system, parameter="Omega", bracket=[2.5, 4.0])
    assert back["Omega_critical"] == pytest.approx(3.0, rel=1e-9)
    assert back["method"] == "bisection"


def test_beck_column_flutter_load():
    """P_cr against Beck's 20.05 EI/L^2: 5e-4 relative (the published value's four digits, +-2.5e-4; the
    16-element discretisation error, measured against 32 elements, is 1e-5); a complex crossing: flutter."""
    system = mechgen.compile("follower_column", {"N": 16, "P": 5.0}, backend="numpy")
    res = mechgen.stability_boundary(system, parameter="P", bracket=[10.0, 25.0])
    assert res["P_critical"] == pytest.approx(20.05, rel=5e-4)
    assert res["crossing"] == "complex" and res["method"] == "bisection"
    assert res["verdict"] == "stable"
    # the merged frequency lies between the two lowest frequencies at the start (they approach each other)
    low = mechgen.stability(system, count=2)["frequencies"][:2]
    assert low[0] < res["frequency_critical"] < low[1]
    fine = mechgen.stability_boundary(system.with_params(N=32), parameter="P", bracket=[10.0, 25.0])
    assert abs(fine["P_critical"] / res["P_critical"] - 1) < 1e-4


def test_a_bracket_on_one_side_says_so_and_a_straddling_one_is_never_refused(column):
    system = mechgen.compile(column, backend="numpy")
    with pytest.raises(ConvergenceError, match="does not straddle") as err:
        mechgen.stability_boundary(system, parameter="P", bracket=[1.0, 5.0])
    assert "stable at P = 1" in str(err.value) and "stable at P = 5" in str(err.value)
    # the stable end's growth rate is exactly 0: before issue 25 this straddling bracket was refused
    assert mechgen.stability_boundary(system, parameter="P", bracket=[8.0, 9.0])["P_critical"] > 8.0
