"""Spinning Timoshenko shafts (model spinning_shaft): closed forms, limits, segments and parts.

References:
* Pinned-pinned uniform spinning Timoshenko shaft (Zu & Han 1992, J. Appl. Mech. 59, S197): with
  u = U sin(k s), psi = Psi cos(k s), k = n pi / L, written for the complex lateral motion
  ux + i uy, the whirl frequencies are the real roots omega of
      (kGA k^2 - rhoA omega^2)(EI k^2 + kGA - rhoI omega^2 + rhoIp Omega omega) = kGA^2 k^2,
  positive roots one whirl sense, negative ones the other (|omega| reported).
* Rayleigh limit (kGA -> oo): (rhoA + rhoI k^2) omega^2 -+ rhoIp Omega k^2 omega - EI k^4 = 0.
* Euler-Bernoulli limit (no rotary inertia, kGA -> oo): omega = k^2 sqrt(EI / rhoA), independent of Omega.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from rotors import shaft

from mechgen.runtime.linear.damped import damped_modes
from mechgen.runtime.fields.mesh import Layout, Part, Segment


def section(E=211e9, G=81.2e9, D=0.05, kappa=None):
    A, I = np.pi / 4 * D**2, np.pi / 64 * D**4
    nu = E / (2 * G) - 1
    kappa = 6 * (1 + nu) / (7 + 6 * nu) if kappa is None else kappa  # Cowper, solid circle
    return A, I, kappa * G * A


def pinned_exact(Omega, count, *, E=211e9, G=81.2e9, rho=7810.0, D=0.05, L=1.0, rotary=1.0, kappa=None):
    """Lowest ``count`` whirl frequencies from the closed-form frequency equation above."""
    A, I, kGA = section(E, G, D, kappa)
    P = np.polynomial.Polynomial
    out = []
    for n in range(1, count + 1):
        k = n * np.pi / L
        poly = P([kGA * k**2, 0, -rho * A]) * P([E * I * k**2 + kGA, rotary * rho * 2 * I * Omega,
                                                -rotary * rho * I]) - kGA**2 * k**2
        roots = poly.roots()
        roots = roots[np.abs(roots.imag) < 1e-9 * np.abs(roots).max()].real
        out += list(np.abs(roots))
    return np.sort(out)[:count]


def whirl_frequencies(system, Omega: float, count: int, sparse: bool | None = None) -> np.ndarray:
    """The ``count`` lowest damped frequencies: dense QR up to 400 unknowns (1e-12 .. 1e-10 here), else
    sparse shift-invert (about 1e-9 relative; also the choice for very unequal masses, where the dense
    M^-1 K loses the low modes to round-off)."""
    system = system.with_params(Omega=Omega)
    mats = system.linear(np.zeros(system.n))
    sparse = system.n > 400 if sparse is None else sparse
    res = damped_modes(mats["M"], mats["D"] + mats["G"], mats["K"], count, sparse=sparse)
    assert np.all(np.abs(res.eigenvalues.real) <= 1e-6 * res.wd)  # undamped: conservative up to round-off
    return res.wd


@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("Omega", [0.0, 3000.0])
def test_pinned_quintic_matches_the_closed_form(Omega, sparse):
    system = shaft({"bc": "pinned-pinned", "discretisation": "quintic", "N": 12})
    found = whirl_frequencies(system, Omega, 8, sparse=sparse)
    np.testing.assert_allclose(found, pinned_exact(Omega, 8), rtol=1e-8)


def test_pinned_two_node_element_converges_at_second_order():
    """timoshenko2: frequency errors fall as h^2 (rate fitted over three meshes, +-0.15)."""
    exact = pinned_exact(2000.0, 4)
    errors = []
    sizes = (16, 32, 64)
    for n in sizes:
        found = whirl_frequencies(shaft({"bc": "pinned-pinned", "discretisation": "timoshenko2", "N": n}), 2000.0, 4)
        errors.append(np.abs(found / exact - 1).max())
    rate = -np.polyfit(np.log(sizes), np.log(errors), 1)[0]
    assert errors[-1] < 1e-5
    assert rate == pytest.approx(2.0, abs=0.15)


def test_rayleigh_and_euler_bernoulli_limits():
    """kappa G_s = 1e4 E_s: Rayleigh's closed form with rotary inertia, Euler-Bernoulli's without (to the shear
    O(1e-6)). A constant kappa: Cowper's tends to 0 as nu = E/2G - 1 -> -1, so a large G alone is no limit."""
    E, rho, D, L, Omega = 211e9, 7810.0, 0.05, 1.0, 4000.0
    A, I = np.pi / 4 * D**2, np.pi / 64 * D**4
    k = np.arange(1, 4) * np.pi / L
    rayleigh = []
    for kk in k:
        for sign in (1, -1):
            roots = np.roots([rho * A + rho * I * kk**2, -sign * rho * 2 * I * Omega * kk**2, -E * I * kk**4])
            rayleigh.append(np.abs(roots).max() if sign == 1 else np.abs(roots).min())
    rayleigh = np.sort(rayleigh)
    stiff = {"bc": "pinned-pinned", "discretisation": "quintic", "N": 12, "G_s": 1e4 * E, "shear": "constant",
             "shear_kappa": 1.0}
    found = whirl_frequencies(shaft(stiff), Omega, 6)
    np.testing.assert_allclose(found, rayleigh, rtol=2e-5)
    eb = np.repeat(k**2 * np.sqrt(E * I / (rho * A)), 2)
    found = whirl_frequencies(shaft({**stiff, "rotary": 0.0}), Omega, 6)
    np.testing.assert_allclose(found, eb, rtol=2e-5)


def test_equal_segments_and_breaks_change_nothing():
    """Three segments of the same section, with breaks at their interfaces, give the uniform shaft's frequencies."""
    layout = Layout(tuple(Segment(length, n, {"D": 0.05}) for length, n in ((0.25, 3), (0.5, 6), (0.25, 3))))
    for disc, tol in (("timoshenko2", 1e-9), ("quintic", 1e-9)):
        uniform = whirl_frequencies(shaft({"bc": "clamped-free", "discretisation": disc, "N": 12}), 1500.0, 8)
        stepped = whirl_frequencies(shaft({"bc": "clamped-free", "discretisation": disc, "N": 12}, layout), 1500.0, 8)
        np.testing.assert_allclose(stepped, uniform, rtol=tol)


def test_stepped_shaft_quintic_and_two_node_elements_converge_together():
    """Overhung three-segment shaft: the quintic element (4 per segment) against the two-node one Richardson-
    extrapolated from 32 and 64 per segment (error ~ h^2): agreement to 3e-8 (sparse shift-invert with the
    Rayleigh-functional refinement on 1 544 first-order unknowns), where the raw 64-element
    frequencies are still 1e-7 .. 3e-5 off."""
    segments = ((0.2, 0.06), (0.15, 0.045), (0.1, 0.03))

    def run(disc, per):
        layout = Layout(tuple(Segment(length, per, {"D": D}) for length, D in segments))
        return whirl_frequencies(shaft({"bc": "clamped-free", "discretisation": disc, "N": per}, layout), 2000.0, 8)

    quintic, coarse, fine = run("quintic", 4), run("timoshenko2", 32), run("timoshenko2", 64)
    np.testing.assert_allclose(quintic, fine + (fine - coarse) / 3, rtol=3e-8)
    assert np.abs(fine / quintic - 1).max() > 1e-5
    # and the quintic element has converged: doubling its mesh moves nothing beyond 1e-9
    np.testing.assert_allclose(run("quintic", 8), quintic, rtol=1e-9)


def test_zero_spin_pairs_split_with_spin():
    """Isotropic shaft at rest: equal pairs; spinning: each pair splits into backward (lower) and forward."""
    system = shaft({"bc": "clamped-free", "discretisation": "quintic", "N": 6})
    rest = whirl_frequencies(system, 0.0, 8)
    np.testing.assert_allclose(rest[0::2], rest[1::2], rtol=1e-9)
    spun = whirl_frequencies(system, 3000.0, 8)
    assert np.all(spun[1::2] - spun[0::2] > 1e-3 * rest[0::2])
    assert np.all((spun[0::2] < rest[0::2]) & (rest[1::2] < spun[1::2]))


def test_part_off_the_mesh_is_a_clear_error():
    from mechgen.errors import InputError

    layout = Layout(parts=(Part("disk", 0.33, {"m": 1.0}),))
    system = shaft({"discretisation": "quintic", "N": 4}, layout)
    with pytest.raises(InputError, match="not at a mesh vertex"):
        system.linear(np.zeros(1))


@pytest.mark.parametrize("disc", ["quintic", "timoshenko2"])
def test_point_disk_on_a_light_shaft_is_a_jeffcott_rotor(disc):
    """A 50 kg disk at mid-span of a light (rho = 1 kg/m^3) pinned shaft: omega = sqrt(k / m_eff) with the
    Timoshenko mid-span stiffness 1/k = L^3/(48 EI) + L/(4 kGA) and m_eff = m + 17/35 m_shaft (Rayleigh's
    energy estimate of the shaft's share; its error here is O((m_shaft/m)^2) = 1e-11)."""
    E, G, D, L, m = 211e9, 81.2e9, 0.02, 1.0, 50.0
    A, I, kGA = section(E, G, D)
    flexibility = L**3 / (48 * E * I) + L / (4 * kGA)
    layout = Layout(parts=(Part("disk", L / 2, {"m": m}),))
    system = shaft({"bc": "pinned-pinned", "discretisation": disc, "N": 4, "D": D, "rho": 1.0}, layout)
    found = whirl_frequencies(system, 0.0, 2, sparse=True)
    np.testing.assert_allclose(found, np.sqrt(1 / (flexibility * (m + 17 / 35 * A * L))), rtol=1e-7)


STEPPED = ((0.2, 0.06), (0.15, 0.045), (0.1, 0.03))


def _stepped(disc: str, per: int, **choices):
    layout = Layout(tuple(Segment(length, per, {"D": D}) for length, D in STEPPED))
    system = shaft({"bc": "clamped-free", "discretisation": disc, "N": per}, layout)
    return replace(system, choices={**system.choices, **choices}, _cache={})


@pytest.mark.parametrize("disc,per,tol", [("quintic", 4, 1e-8), ("timoshenko2", 16, 1e-10)])
def test_substructures_joined_by_multipliers_match_direct_assembly(disc, per, tol):
    """Yu & Cleghorn's way: segments as separate substructures, continuity of displacements (and, for the
    quintic element's slope dofs, of shear force kGA (u_s - psi) and moment EI psi_s) as constraints reduced
    to a standard eigenproblem by their null space: the same frequencies as direct assembly."""
    assembled = whirl_frequencies(_stepped(disc, per), 2000.0, 8)
    joined = _stepped(disc, per, joints="multiplier")
    assert joined.n <= _stepped(disc, per).n  # reduced to a standard problem, not enlarged
    np.testing.assert_allclose(whirl_frequencies(joined, 2000.0, 8), assembled, rtol=tol)


def test_penalty_supports_and_multiplier_joints_as_in_the_paper():
    """Penalty boundary conditions (factor 1e6 on the largest stiffness diagonal) converge to the clamped
    frequencies as 1/factor: within 1e-5 of elimination; bordered multipliers for every constraint agree too."""
    exact = whirl_frequencies(_stepped("quintic", 4), 2000.0, 8)
    paper = _stepped("quintic", 4, joints="multiplier", constraints="penalty")
    penalised = whirl_frequencies(paper, 2000.0, 8)
    assert 1e-8 < np.abs(penalised / exact - 1).max() < 1e-5
    bordered = _stepped("quintic", 4, joints="multiplier", constraints="multiplier")
    np.testing.assert_allclose(whirl_frequencies(bordered, 2000.0, 8), exact, rtol=1e-6)


def test_shear_coefficients_of_hollow_sections():
    """Cowper (1966) and Hutchinson (2001) shear coefficients for a hollow circle (m = d/D, nu = E/2G - 1),
    as written in ROSS's shaft element: each selectable law gives the frequencies of the constant-kappa
    shaft with that value, and the three differ (the laws are not silently the same)."""
    E, G, D, d = 211e9, 81.2e9, 0.05, 0.03
    nu, m2 = E / (2 * G) - 1, (d / D) ** 2
    cowper = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)
    hutchinson = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 12 * nu + 4 * nu**2) * (1 + m2) ** 2
                                                 + 4 * (5 + 6 * nu + 2 * nu**2) * m2)
    base = {"bc": "pinned-pinned", "discretisation": "quintic", "N": 6, "d": d}
    results = {}
    for law, kappa in (("cowper", cowper), ("hutchinson", hutchinson)):
        results[law] = whirl_frequencies(shaft({**base, "shear": law}), 1000.0, 8)
        constant = whirl_frequencies(shaft({**base, "shear": "constant", "shear_kappa": kappa}), 1000.0, 8)
        np.testing.assert_allclose(results[law], constant, rtol=1e-10)
    assert np.abs(results["cowper"] / results["hutchinson"] - 1).max() > 1e-5


def test_hard_case_free_free_shaft_drops_rigid_modes():
    """Singular K: an unsupported shaft has four rigid modes (s = 0), which never count as frequencies; the
    flexible ones of a stiff-shear shaft without rotary inertia are the free-free Euler-Bernoulli beam's,
    beta_n L = 4.730040744862704, 7.853204624095838 (roots of cos(bL) cosh(bL) = 1), each twice."""
    E, rho, D, L = 211e9, 7810.0, 0.05, 1.0
    A, I = np.pi / 4 * D**2, np.pi / 64 * D**4
    beta = np.array([4.730040744862704, 7.853204624095838]) / L
    eb = np.repeat(beta**2 * np.sqrt(E * I / (rho * A)), 2)
    system = shaft({"bc": "free-free", "discretisation": "quintic", "N": 8, "G_s": 1e4 * E, "shear": "constant",
                    "shear_kappa": 1.0, "rotary": 0.0})
    mats = system.linear(np.zeros(system.n))
    res = damped_modes(mats["M"], mats["D"] + mats["G"], mats["K"], 4)
    assert len(res.real_eigenvalues) == 8 and np.abs(res.real_eigenvalues).max() < 1e-7 * res.scale  # round-off
    np.testing.assert_allclose(res.wd, eb, rtol=1e-5)


def test_hard_case_stiff_bearings_tend_to_pinned_supports():
    """Bearings of 1e13 N/m (shaft stiffness ~1e6 N/m): the frequencies of the pinned-pinned shaft with the
    same disk, to the support compliance O(1e-7); the solver copes with the 1e7 stiffness contrast."""
    disk = Part("disk", 0.5, {"m": 30.0, "Id": 0.2, "Ip": 0.35})
    soft = Layout(parts=(disk, Part("bearing", 0.0, {"kxx": 1e13, "kyy": 1e13}),
                         Part("bearing", 1.0, {"kxx": 1e13, "kyy": 1e13})))
    spring = whirl_frequencies(shaft({"bc": "free-free", "discretisation": "quintic", "N": 4}, soft), 1500.0, 6)
    pinned = whirl_frequencies(shaft({"bc": "pinned-pinned", "discretisation": "quintic", "N": 4},
                                     Layout(parts=(disk,))), 1500.0, 6)
    np.testing.assert_allclose(spring, pinned, rtol=1e-6)


def test_hard_case_high_speed_stays_conservative():
    """Omega = 1e5 rad/s (far above every critical speed): sparse and dense solvers agree to 1e-9 and every
    eigenvalue stays on the imaginary axis (no spurious growth from round-off)."""
    layout = Layout(parts=(Part("disk", 0.5, {"m": 30.0, "Id": 0.2, "Ip": 0.35}),
                           Part("bearing", 0.0, {"kxx": 1e7, "kyy": 5e6}), Part("bearing", 1.0, {"kxx": 1e7, "kyy": 5e6})))
    system = shaft({"discretisation": "quintic", "N": 4}, layout)
    dense = whirl_frequencies(system, 1e5, 8, sparse=False)
    np.testing.assert_allclose(whirl_frequencies(system, 1e5, 8, sparse=True), dense, rtol=1e-9)


def test_two_node_element_follows_a_parameter_change():
    """timoshenko2's shape functions hold phi = 12 EI/(kGA h^2): changing G_s on the same system (a sweep) must
    rebuild them, giving the frequencies of a shaft built with that G_s from the start."""
    system = shaft({"bc": "pinned-pinned", "discretisation": "timoshenko2", "N": 16})
    whirl_frequencies(system, 0.0, 4)
    system = system.with_params(G_s=20e9)
    fresh = shaft({"bc": "pinned-pinned", "discretisation": "timoshenko2", "N": 16, "G_s": 20e9})
    np.testing.assert_allclose(whirl_frequencies(system, 0.0, 4), whirl_frequencies(fresh, 0.0, 4), rtol=1e-12)
