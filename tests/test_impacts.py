"""Compliant impacts of the viscoelastic_impact model against closed forms (Butcher & Segalman 2000).

References (tests/impact_reference.py, each derived in its docstring; paper: E. A. Butcher and
D. J. Segalman, "Characterizing damping and restitution in compliant impacts via modified K-V and
higher-order linear viscoelastic models", ASME J. Appl. Mech. 67 (2000) 831-834):

* half-period Kelvin-Voigt, e = exp(-zeta pi / sqrt(1 - zeta^2)) (eq. 4), no release from zeta = 1;
* modified Kelvin-Voigt, e = exp(-2 zeta q(zeta)), q = acos(zeta)/sqrt(1 - zeta^2) (acosh above 1), the
  paper's eqs. 9-11, tending to exp(-2) at zeta = 1;
* Maxwell, the half-period value (section 3, eq. 16);
* standard linear solid: the exact solution of its linear third-order equation (eq. 19) by the matrix
  exponential, and its first-order expansion e = e_MKV (1 + epsilon e1(zeta)) for small epsilon;
* Hunt-Crossley: ln((1 + a)/(1 - a e)) = a (1 + e), a = alpha v_in, from integrating
  m v dv/dx = -k x^n (1 + alpha v) over the contact (independent of k, m, n).
"""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.errors import ModelError

sys.path.insert(0, str(Path(__file__).parent))
import impact_reference as ref  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
LAWS = ("kelvin_voigt", "modified_kelvin_voigt", "maxwell", "standard_linear", "hunt_crossley")


def reference(law: str, zeta: float, epsilon: float = 0.1) -> float:
    """The closed-form (or exact linear) restitution of a law; Hunt-Crossley at a = 3 pi zeta / 2."""
    if law == "kelvin_voigt":
        return ref.kv_restitution(zeta)
    if law == "modified_kelvin_voigt":
        return ref.mkv_restitution(zeta)
    if law == "maxwell":
        return ref.maxwell_restitution(zeta)
    if law == "standard_linear":
        return ref.sls_restitution(zeta, epsilon)
    return ref.hc_restitution(1.5 * math.pi * zeta)


@pytest.fixture(scope="module")
def systems():
    return {law: mechgen.compile("viscoelastic_impact", {"law": law}, free=["zeta", "k", "m", "v_in", "epsilon",
                                                                             "n"])
            for law in LAWS}


def impact(system, **options):
    options = {"t_end": 60.0, "v0": {"x": 1.0}, **options}
    return mechgen.impact(system, **options).outputs


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("zeta", [0.05, 0.4, 0.95])
def test_restitution_meets_the_closed_forms(systems, law, zeta):
    e = impact(systems[law].with_params(zeta=zeta), rtol=1e-12, atol=1e-14)["restitution"]
    expected = reference(law, zeta)
    assert e == pytest.approx(expected, rel=1e-8, abs=1e-14)


@pytest.mark.parametrize("law", ["kelvin_voigt", "modified_kelvin_voigt", "maxwell"])
def test_contact_duration_and_energy_lost(systems, law):
    zeta = 0.3
    out = impact(systems[law].with_params(zeta=zeta), rtol=1e-12, atol=1e-14)
    time = {"kelvin_voigt": ref.kv_contact_time, "modified_kelvin_voigt": ref.mkv_contact_time,
            "maxwell": ref.maxwell_contact_time}[law](zeta)
    assert out["contact_duration"] == pytest.approx(time, rel=1e-9)
    e = reference(law, zeta)
    if law == "modified_kelvin_voigt":
        # release with the spring still compressed: E(t_r) = E0 (e^2 + 4 zeta^2 e^2) (impact_reference)
        lost = 1 - e**2 * (1 + 4 * zeta**2)
    else:
        lost = 1 - e**2
    assert out["energy_lost"] == pytest.approx(lost, rel=1e-9)


def test_overdamped_laws():
    """zeta >= 1: half-period K-V and Maxwell never release (e = 0, perfectly plastic); the modified K-V does,
    with e(1) = exp(-2) (paper, section 2)."""
    for law in ("kelvin_voigt", "maxwell"):
        out = impact(mechgen.compile("viscoelastic_impact", {"law": law, "zeta": 1.5}), t_end=40.0)
        assert out["released"] is False and out["restitution"] == 0.0
    out = impact(mechgen.compile("viscoelastic_impact", {"law": "modified_kelvin_voigt", "zeta": 1.0}),
                 rtol=1e-12, atol=1e-14)
    assert out["restitution"] == pytest.approx(math.exp(-2.0), rel=1e-8)
    for zeta in (2.0, 5.0):
        out = impact(mechgen.compile("viscoelastic_impact", {"law": "modified_kelvin_voigt", "zeta": zeta}),
                     rtol=1e-12, atol=1e-14)
        assert out["restitution"] == pytest.approx(ref.mkv_restitution(zeta), rel=1e-8)


def test_undamped_impact_is_elastic(systems):
    for law in ("kelvin_voigt", "modified_kelvin_voigt", "maxwell", "hunt_crossley"):
        out = impact(systems[law].with_params(zeta=0.0), rtol=1e-12, atol=1e-14)
        assert out["restitution"] == pytest.approx(1.0, rel=1e-9), law
        assert abs(out["energy_lost"]) < 1e-9


def test_error_falls_with_the_tolerance(systems):
    """The restitution error of the Kelvin-Voigt impact against eq. 4 over a tolerance ladder: it falls, with a
    measured order (slope of log error on log rtol) well above zero."""
    zeta, system = 0.3, systems["kelvin_voigt"].with_params(zeta=0.3)
    exact = ref.kv_restitution(zeta)
    rtols = [1e-5, 1e-7, 1e-9, 1e-11]
    errors = [abs(impact(system, rtol=r, atol=r * 1e-2, method="RK45")["restitution"] - exact) / exact
              for r in rtols]
    slope = np.polyfit(np.log10(rtols), np.log10(np.maximum(errors, 1e-16)), 1)[0]
    assert errors[-1] < 1e-8
    assert errors[-1] < errors[0] / 100
    assert slope > 0.5, (errors, slope)


def test_standard_linear_solid_exact_and_first_order(systems):
    """Exact: the linear third-order solution (expm, impact_reference.sls_release). First order in epsilon:
    e_MKV (1 + epsilon e1(zeta)); the simulation's distance to it shrinks like epsilon^2."""
    system = systems["standard_linear"]
    for zeta, eps in ((0.2, 0.1), (0.6, 0.3), (1.5, 0.05)):
        e = impact(system.with_params(zeta=zeta, epsilon=eps), rtol=1e-12, atol=1e-14, method="Radau")["restitution"]
        assert e == pytest.approx(ref.sls_restitution(zeta, eps), rel=1e-8)
    zeta = 0.3
    gaps = []
    for eps in (4e-3, 2e-3):
        e = impact(system.with_params(zeta=zeta, epsilon=eps), rtol=1e-12, atol=1e-14, method="Radau")["restitution"]
        gaps.append(abs(e - ref.sls_restitution_first_order(zeta, eps)))
    assert gaps[1] < gaps[0] / 3  # second order: a factor 4 for half the epsilon


def test_hunt_crossley_depends_on_alpha_v_in_only(systems):
    """e is the same for any k, m, n at the same a = alpha v_in (alpha = 3 pi zeta / (2 v_in) in the model)."""
    base = systems["hunt_crossley"]
    values = []
    for k, m, n, v in ((1.0, 1.0, 1.5, 1.0), (1e4, 0.2, 1.0, 3.0), (50.0, 7.0, 2.5, 0.1)):
        out = impact(base.with_params(zeta=0.2, k=k, m=m, n=n, v_in=v), v0={"x": v}, rtol=1e-12, atol=1e-14 * v)
        values.append(out["restitution"])
    assert np.ptp(values) < 1e-9
    assert values[0] == pytest.approx(ref.hc_restitution(1.5 * math.pi * 0.2), rel=1e-9)


def test_stiff_contact_with_the_implicit_integrator(systems):
    """k/m = 1e10: the contact lasts pi/omega_d ~ 3e-5 s; Radau with the generated Jacobian resolves it in a
    bounded number of steps and meets eq. 4."""
    system = systems["kelvin_voigt"].with_params(zeta=0.2, k=1e10)
    out = mechgen.impact(system, t_end=1e-3, v0={"x": 1.0}, method="Radau", rtol=1e-10, atol=1e-16,
                         max_steps=5000).outputs
    assert out["restitution"] == pytest.approx(ref.kv_restitution(0.2), rel=1e-7)
    assert out["contact_duration"] == pytest.approx(math.pi / (1e5 * math.sqrt(1 - 0.04)), rel=1e-8)


def test_standard_linear_without_dashpot_is_refused(systems):
    """zeta = 0 leaves the standard linear solid without a dashpot (y' = (k1 (x - y) - k2 y) / c unbounded):
    folded into the kernels it is refused at compile time naming zeta; free, the first rate evaluation
    fails naming the kernel (never a silent answer)."""
    from mechgen.errors import KernelError

    with pytest.raises(ModelError, match="zeta"):
        mechgen.compile("viscoelastic_impact", {"law": "standard_linear", "zeta": 0.0}, free=[])
    for loop in ("c", "python"):  # both event loops name the mode, the kernel output and the parameter
        with pytest.raises(KernelError, match="in mode contact.*'rates' output g\\[0\\] \\(internal variable 'y'\\) "
                                              "= nan.*zeta: 0") as info:
            mechgen.impact(systems["standard_linear"].with_params(zeta=0.0), t_end=10.0, loop=loop)
        assert "Traceback" not in str(info.value)


def test_scene_single_value_and_names(tmp_path):
    """scenes/impact_models.toml with --set zeta=0.3: one value, the issue's output names."""
    out = tmp_path / "r.json"
    proc = subprocess.run([sys.executable, "-m", "mechgen", "run", str(ROOT / "scenes" / "impact_models.toml"),
                           "--set", "zeta=0.3", "--json", str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(out.read_text())["analyses"][0]["outputs"]
    assert result["zeta"] == [0.3]
    assert set(result["restitution"]) == set(LAWS)
    for law in LAWS:
        assert result["restitution"][law][0] == pytest.approx(reference(law, 0.3), rel=1e-8)
