"""Plane continua end to end (models, scenes, PlaneSystem) against closed forms, Bessel zeros and convergence rates."""
import math

import numpy as np
import pytest
import sympy as sp
from scipy.special import jn_zeros

import mechgen
from mechgen.analyses.plane_states import plane_steady
from mechgen.errors import InputError
from mechgen.runtime.linear.modes import modes as solve_modes
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.plane import gradient, rectangle
from mechgen.symbolic.plane_materials import linear_elastic

E, NU, RHO_G, R = 1.0, 0.3, 1.0, 1.0
MU, LAM = E / (2 * (1 + NU)), E * NU / (1 - NU**2)  # plane stress lambda*


def membrane_exact():
    """u_y(0, 0) and the strain energy of the fixed disk under gravity: u = (0, -rho_g (R^2 - r^2) / (2 (lambda* + 3 mu)))
    (checked to solve Navier's equations in test_membrane_closed_form_solves_navier)."""
    c = RHO_G / (2 * (LAM + 3 * MU))
    return -c * R**2, math.pi * RHO_G**2 * R**4 / (8 * (LAM + 3 * MU))


def test_membrane_closed_form_solves_navier():
    """mu lap u + (lambda* + mu) grad div u + b = 0 with b = (0, -rho_g), u = 0 on r = R, and U = 1/2 int b.u dA."""
    x, y, r, th = sp.symbols("x y r theta", real=True)
    mu, lam, g, Rs = sp.symbols("mu lambda rho_g R", positive=True)
    uy = -g * (Rs**2 - x**2 - y**2) / (2 * (lam + 3 * mu))
    u = sp.Matrix([0, uy])
    div = sp.diff(u[0], x) + sp.diff(u[1], y)
    for i, xi in enumerate((x, y)):
        lap = sp.diff(u[i], x, 2) + sp.diff(u[i], y, 2)
        body = -g if i == 1 else 0
        assert sp.simplify(mu * lap + (lam + mu) * sp.diff(div, xi) + body) == 0
    assert sp.simplify(uy.subs({x: Rs * sp.cos(th), y: Rs * sp.sin(th)})) == 0
    U = sp.integrate(sp.Rational(1, 2) * (-g) * uy.subs({x: r, y: 0}) * 2 * sp.pi * r, (r, 0, Rs))
    assert sp.simplify(U - sp.pi * g**2 * Rs**4 / (8 * (lam + 3 * mu))) == 0


@pytest.fixture(scope="module")
def membrane():
    return mechgen.compile("membrane_gravity", {"E": E, "nu": NU, "rho_g": RHO_G, "R": R},
                           kernels=("residual", "tangent", "outputs"))


def test_membrane_scene_outputs_match_the_closed_form():
    """scenes/membrane_gravity.toml: u_y(0) and U within 1e-6 (P2, curved rim, h = 0.1: measured 2e-7 and 4e-7),
    the rim's reaction the whole weight pi R^2 rho_g (to round-off: equilibrium of the discrete system)."""
    from mechgen.scene.run import run_scene

    out = run_scene("scenes/membrane_gravity.toml")["analyses"][0]["outputs"]
    uy, U = membrane_exact()
    assert out["center_displacement"][1] == pytest.approx(uy, rel=1e-6)
    assert abs(out["center_displacement"][0]) < 1e-7  # u_x = 0 exactly; the O-grid mesh is not mirror-symmetric
    assert out["strain_energy"] == pytest.approx(U, rel=1e-6)
    assert out["potential_energy"] == pytest.approx(-U, rel=1e-6)  # Clapeyron: Pi = -U at equilibrium
    # the isoparametric disk's area is pi R^2 to O(h^4) (2e-7 at h = 0.1); the discrete balance is exact
    assert out["reactions"]["outer"]["uy"] == pytest.approx(math.pi * R**2 * RHO_G, rel=1e-6)
    r2 = np.sum(np.array([[0.5, 0.0], [0.0, -0.5], [0.6, 0.6]]) ** 2, axis=1)
    expected = -RHO_G * (R**2 - r2) / (2 * (LAM + 3 * MU))
    assert np.allclose(np.array(out["probe_displacement"])[:, 1], expected, rtol=1e-5)


def test_rim_reaction_is_the_weight_of_the_discrete_disk(membrane):
    """Sum of r over all dofs = rho_g * (the mesh's area) in y, and the free rows are zero at equilibrium: the held
    rim's reaction equals rho_g times the area the quadrature integrates, to round-off."""
    system = membrane.with_params(h=0.2)
    out = plane_steady(system, {})
    area = float(np.sum(system.disc.pieces[0].weights))
    assert out["reactions"]["outer"]["uy"] == pytest.approx(RHO_G * area, rel=1e-12)


def _errors(system, element, edges, hs):
    uy, U = membrane_exact()
    out = []
    for h in hs:
        res = plane_steady(system.with_params(element=element, h=h, edges=edges), {"points": {"c": [0.0, 0.0]}})
        out.append(abs(res["strain_energy"] - U) / U)
    return np.array(out)


@pytest.mark.parametrize("element, edges, rate", [("P2", "straight", 2), ("P2", "curved", 4), ("Q2", "curved", 4),
                                                  ("P1", "curved", 2), ("Q1", "curved", 2)])
def test_membrane_convergence_rates(membrane, element, edges, rate):
    """The exact solution is quadratic, so P2/Q2 reproduce it on the exact disk: their error is the boundary's.
    Straight-sided edges (a polygon) give O(h^2) in energy, isoparametric curved edges O(h^4); P1/Q1 O(h^2)
    (energy error ~ h^{2p}, p = 1). Measured rates 1.96-2.02, 3.95-4.14, 4.00, 1.98, 2.00 (h = 0.2, 0.1, 0.05)."""
    e = _errors(membrane, element, edges, (0.2, 0.1, 0.05))
    rates = np.log2(e[:-1] / e[1:])
    assert np.all(np.abs(rates - rate) < 0.3), rates


def bessel_frequencies(count):
    """omega of a unit drum (P = rho = R = 1): the zeros j_mn of J_m, each m >= 1 twice."""
    zeros = sorted((z, m) for m in range(8) for z in jn_zeros(m, 4))
    out = [z for z, m in zeros for _ in range(1 if m == 0 else 2)]
    return np.array(out[:count])


def test_drum_modes_against_bessel_zeros():
    """scenes/drum_modes.toml: the first eight frequencies within 5e-5 of j_mn (measured 4.4e-5 at h = 0.1)."""
    from mechgen.scene.run import run_scene

    out = run_scene("scenes/drum_modes.toml")["analyses"][0]["outputs"]
    assert np.allclose(out["frequencies"], bessel_frequencies(8), rtol=5e-5)


def test_drum_eigenvalues_converge_at_twice_the_order():
    """Eigenvalue error ~ h^{2p}: P2 with curved edges 3.9-4.0 (measured), straight 2.1-2.3 (boundary-limited)."""
    drum = mechgen.compile("drum", kernels=("linear",))
    exact = bessel_frequencies(8)
    for edges, rate in (("curved", 4), ("straight", 2)):
        errors = []
        for h in (0.2, 0.1, 0.05):
            L = drum.with_params(h=h, edges=edges).linear()
            errors.append(np.max(np.abs(solve_modes(L["M"], L["K"], count=8).frequencies[:8] - exact) / exact))
        rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        assert np.all(np.abs(rates - rate) < 0.35), (edges, rates)


def uniaxial_model():
    """A rectangle pressed by P on its right edge (edge potential P n.u), rollers on the left (u_x = 0) and bottom
    (u_y = 0): the exact plane stress state is sigma_xx = -P, u_x = -P x / E, u_y = nu P y / E."""
    m = Model("uniaxial_plate")
    m.params(Param("E", 2.0, "Pa", positive=True), Param("nu", 0.25, ""), Param("P", 0.1, "Pa"),
             Param("Lx", 2.0, "m", positive=True), Param("Ly", 1.0, "m", positive=True))
    m.plane("ux", "uy", domain=rectangle("Lx", "Ly"), group="u", element="P1", h=0.25)

    @m.potential_density
    def potential(u, p):
        return linear_elastic(gradient(u, "ux", "uy"), p.E, p.nu, "stress")

    @m.edge_potential("right")
    def pressure(u, p, n):
        return p.P * (n.x * u.ux + n.y * u.uy)

    @m.boundary
    def boundary():
        return [fix("ux", "left"), fix("uy", "bottom")]
    return m


@pytest.mark.parametrize("element", ["P1", "P2", "Q1", "Q2"])
def test_edge_pressure_gives_the_uniform_state_exactly(element):
    """A linear field is in every element's space: the solution is exact to round-off (a patch test through the
    whole pipeline: edge kernel, outward normal, held components, stresses at points, reactions)."""
    system = mechgen.compile(uniaxial_model(), {"element": element})
    out = plane_steady(system, {"points": {"a": [1.3, 0.7]}})
    ux, uy = out["a_displacement"]
    assert ux == pytest.approx(-0.1 * 1.3 / 2.0, rel=1e-10) and uy == pytest.approx(0.25 * 0.1 * 0.7 / 2.0, rel=1e-10)
    assert np.allclose(out["a_stress"], [[-0.1, 0.0], [0.0, 0.0]], atol=1e-12)
    assert out["reactions"]["left"]["ux"] == pytest.approx(0.1 * 1.0, rel=1e-10)  # the wall pushes back: +P Ly


def test_bad_plane_input_is_refused(membrane):
    with pytest.raises(InputError, match="h"):
        membrane.with_params(h=-1.0)
    with pytest.raises(InputError, match="element"):
        membrane.with_params(element="P3")
    with pytest.raises(InputError, match="not in the mesh"):
        coarse = membrane.with_params(h=0.5)
        coarse.field_at(np.zeros(coarse.n), [[2.0, 0.0]])
    annulus = mechgen.compile("annulus_gravity", {"a": 1.5, "b": 1.0}, kernels=("residual",))
    with pytest.raises(InputError, match="inner radius"):
        annulus.n
    from mechgen.runtime.plane.mesh import rectangle as rect

    with pytest.raises(InputError, match="outer"):
        membrane.with_mesh(rect(0, 1, 0, 1, 0.5, "P1"))


def test_annulus_scene_against_its_closed_form():
    """scenes/annulus_gravity.toml (P2, curved edges, h = 0.05) against the annulus's closed form (Michell's n = 1
    terms with logarithms, mechgen.runtime.plane.closed_forms, checked symbolically in test_plane_closed_forms):
    u at (0, a) within 1e-5 (measured 4.3e-6), the strain energy within 1e-6 (measured 2.0e-7), the rim's reaction
    the annulus's weight pi (b^2 - a^2) rho_g."""
    from mechgen.runtime.plane.closed_forms import PlaneElastic, annulus_field, annulus_strain_energy
    from mechgen.scene.run import run_scene

    out = run_scene("scenes/annulus_gravity.toml")["analyses"][0]["outputs"]
    mat = PlaneElastic(1.0, 0.3, "stress")
    exact = annulus_field(np.array([0.0]), np.array([0.5]), 0.5, 1.0, mat, 1.0)
    assert out["hole_top_displacement"][1] == pytest.approx(exact.u[0, 1], rel=1e-5)
    assert out["strain_energy"] == pytest.approx(annulus_strain_energy(0.5, 1.0, mat, 1.0), rel=1e-6)
    assert out["reactions"]["outer"]["uy"] == pytest.approx(math.pi * (1.0 - 0.25), rel=1e-6)
    assert np.allclose(out["hole_top_stress"][1], [0.0, 0.0], atol=2e-3 * np.max(np.abs(out["hole_top_stress"])))  # free edge


def test_annulus_energy_converges_at_the_boundarys_rate():
    """No polynomial solves the annulus, yet P2's energy error still falls as h^4 on curved edges and h^2 on
    straight ones (measured 3.75-4.01 and 2.00-2.03): the element is not what limits it."""
    from mechgen.runtime.plane.closed_forms import PlaneElastic, annulus_strain_energy

    system = mechgen.compile("annulus_gravity", kernels=("residual", "tangent", "outputs"))
    U = annulus_strain_energy(0.5, 1.0, PlaneElastic(1.0, 0.3, "stress"), 1.0)
    for edges, rate in (("curved", 4), ("straight", 2)):
        e = np.array([abs(plane_steady(system.with_params(h=h, edges=edges), {})["strain_energy"] - U) / U
                      for h in (0.2, 0.1, 0.05)])
        rates = np.log2(e[:-1] / e[1:])
        assert np.all(np.abs(rates - rate) < 0.4), (edges, rates)


def test_a_weak_form_load_equals_its_potential(membrane):
    """The weight written as a weak form (test.uy rho_g: not derived from a potential) gives the potential's
    solution: the weak form's residual is dW/dtest, the same pointwise force."""
    m = Model("membrane_weak")
    m.params(Param("E", E, "Pa", positive=True), Param("nu", NU, ""), Param("rho_g", RHO_G, "N/m^3"),
             Param("R", R, "m", positive=True))
    from mechgen.symbolic.plane import disk

    m.plane("ux", "uy", domain=disk("R"), group="u", element="P2", h=0.2)

    @m.potential_density
    def potential(u, p):
        return linear_elastic(gradient(u, "ux", "uy"), p.E, p.nu, "stress")

    @m.weak_form
    def weight(test, u, p):
        return test.uy * p.rho_g

    @m.boundary
    def boundary():
        return [fix("u", "outer")]

    weak = plane_steady(mechgen.compile(m), {"points": {"c": [0.0, 0.0]}})
    energy = plane_steady(membrane.with_params(h=0.2), {"points": {"c": [0.0, 0.0]}})
    assert np.allclose(weak["c_displacement"], energy["c_displacement"], rtol=1e-12, atol=1e-15)


def test_a_point_load_on_a_drum_matches_greens_function():
    """A point force F at the centre of a drum under tension P: w = F ln(R/r)/(2 pi P) away from the point (the
    plane Green's function with w(R) = 0). P2 at h = 0.05: within 2e-5 at r = 0.5 and 0.7 (measured 3e-8, 1e-5);
    the rim carries the whole force (-F, to round-off)."""
    m = Model("drum_point")
    m.params(Param("P", 2.0, "N/m", positive=True), Param("F", 1.0, "N"), Param("R", 1.0, "m", positive=True),
             Param("x0", 0.0, "m"))
    from mechgen.symbolic.plane import disk

    m.plane("w", domain=disk("R"), element="P2", h=0.05)

    @m.potential_density
    def potential(u, p):
        return p.P / 2 * (u.w_x**2 + u.w_y**2)

    @m.point_potential_at("centre", "x0", 0.0)
    def load(u, p):
        return -p.F * u.w

    @m.boundary
    def boundary():
        return [fix("w", "outer")]

    out = plane_steady(mechgen.compile(m), {"probe": [[0.5, 0.0], [0.0, 0.7]]})
    r = np.array([0.5, 0.7])
    assert np.allclose(np.array(out["probe_displacement"])[:, 0], np.log(1 / r) / (4 * np.pi), rtol=2e-5)
    assert out["reactions"]["outer"]["w"] == pytest.approx(-1.0, rel=1e-12)
    with pytest.raises(InputError, match="not in the mesh"):
        mechgen.compile(m, {"x0": 3.0}).n


def test_nodal_fields_of_the_membrane_converge_to_its_closed_form(membrane):
    """``nodal = true`` against Michell's field u_y = c (r^2 - R^2), c = rho_g/(2(lambda* + 3 mu)), eps_yy = 2 c y
    (P2, curved edges, h = 0.2, 0.1, 0.05). Measured: nodal displacement error 1.2e-4, 1.6e-5, 2.0e-6 of c (rate 3);
    the averaged nodal strain 3.7e-3, 9.4e-4, 2.4e-4 (rate 2: the rim's isoparametric cells; inside r < 0.9 the
    errors are 6e-4, 3e-5, 3e-7). The nodal stress is Hooke's law of the nodal gradient to round-off (the kernel
    evaluated at the nodal jets)."""
    c = RHO_G / (2 * (LAM + 3 * MU))
    eu, es = [], []
    for h in (0.2, 0.1, 0.05):
        out = plane_steady(membrane.with_params(h=h), {"nodal": True})["nodal"]
        x, y = np.array(out["x"]), np.array(out["y"])
        eu.append(np.abs(np.array(out["displacement"]["uy"]) - c * (x**2 + y**2 - R**2)).max() / c)
        es.append(np.abs(np.array(out["strain"]["yy"]) - 2 * c * y).max() / (2 * c))
        eps = np.array([out["strain"]["xx"], out["strain"]["yy"], out["strain"]["xy"]])
        sigma_yy = LAM * (eps[0] + eps[1]) + 2 * MU * eps[1]
        assert np.allclose(np.array(out["stress"]["uy"])[:, 1], sigma_yy, rtol=0, atol=1e-12)
    assert np.all(np.log2(np.array(eu[:-1]) / np.array(eu[1:])) > 2.7), eu
    assert np.all(np.log2(np.array(es[:-1]) / np.array(es[1:])) > 1.8), es
