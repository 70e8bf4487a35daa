"""Plane continua: the derivation on the local piece (mechgen.symbolic.plane) against hand-derived closed forms."""
import pytest
import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.plane import NORMAL, X, Y, derive_plane, disk, gradient, plane_jet, rectangle
from mechgen.symbolic.plane_materials import lame, linear_elastic, neo_hookean, saint_venant_kirchhoff
from mechgen.symbolic.specialize import all_free


def elastic_model(law=linear_elastic, plane="stress"):
    m = Model("plane_test")
    m.params(Param("E", 1.0, "Pa", positive=True), Param("nu", 0.3, ""), Param("b", 1.0, "N/m^3"),
             Param("rho", 1.0, "kg/m^3", positive=True), Param("R", 1.0, "m", positive=True),
             Param("plane", plane, "", choices=("stress", "strain")))
    m.plane("ux", "uy", domain=disk("R"), group="u")

    @m.potential_density
    def potential(u, p):
        return law(gradient(u, "ux", "uy"), p.E, p.nu, p.plane) + p.b * u.uy

    @m.kinetic_density
    def kinetic(u, p):
        return p.rho / 2 * (u.ux_t**2 + u.uy_t**2)

    @m.boundary
    def boundary():
        return [fix("u", "outer")]
    return m


def hooke(E, nu, plane):
    """Plane Hooke's law C_ijkl = lambda* d_ij d_kl + mu (d_ik d_jl + d_il d_jk), written by hand."""
    mu = E / (2 * (1 + nu))
    lam = E * nu / (1 - nu**2) if plane == "stress" else E * nu / ((1 + nu) * (1 - 2 * nu))
    d = lambda i, j: 1 if i == j else 0  # noqa: E731
    return lambda i, j, k, l: lam * d(i, j) * d(k, l) + mu * (d(i, k) * d(j, l) + d(i, l) * d(j, k))


@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_tangent_of_linear_elasticity_is_hookes_tensor(plane):
    """d rho/dj between gradient jets (u_i,j) is C_ijkl; the body force sits on the value jet u_y."""
    model = elastic_model(plane=plane)
    eqs = derive_plane(model, all_free(model) if plane == "stress" else _strain(model))
    assert eqs.jets == (("ux", ""), ("ux", "x"), ("ux", "y"), ("uy", ""), ("uy", "x"), ("uy", "y"))
    K = eqs.local.jacobian(eqs.local.residual, "q")
    E = [s for s in eqs.local.params if s.name == "E"][0]
    nu = [s for s in eqs.local.params if s.name == "nu"][0]
    C = hooke(E, nu, plane)
    where = {("ux", "x"): (0, 0), ("ux", "y"): (0, 1), ("uy", "x"): (1, 0), ("uy", "y"): (1, 1)}
    for a, ja in enumerate(eqs.jets):
        for b, jb in enumerate(eqs.jets):
            expected = C(*where[ja], *where[jb]) if ja in where and jb in where else 0
            assert sp.simplify(K[a, b] - expected) == 0, (ja, jb)
    b_sym = [s for s in eqs.local.params if s.name == "b"][0]
    rho0 = eqs.local.residual.subs({s: 0 for s in (*eqs.local.q, *eqs.local.a)})
    assert list(rho0) == [0, 0, 0, b_sym, 0, 0]
    M = eqs.local.jacobian(eqs.local.residual, "a")
    rho = [s for s in eqs.local.params if s.name == "rho"][0]
    assert M[0, 0] == rho and M[3, 3] == rho and sum(abs(x) for x in M) == 2 * rho
    assert eqs.local.position == (X, Y)


def _strain(model):
    from mechgen.symbolic.specialize import specialize

    return specialize(model, {"plane": "strain"}, free=("E", "nu", "b", "rho", "R"))


def test_plane_stress_lambda_is_the_condensed_one():
    """lambda* of plane stress = 2 lambda mu/(lambda + 2 mu) with lambda, mu of the solid (sigma_33 = 0 condensed)."""
    E, nu = sp.symbols("E nu", positive=True)
    lam3, mu = lame(E, nu, "strain")
    lam_star, mu2 = lame(E, nu, "stress")
    assert sp.simplify(lam_star - 2 * lam3 * mu / (lam3 + 2 * mu)) == 0 and mu2 == mu


@pytest.mark.parametrize("law", [saint_venant_kirchhoff, neo_hookean])
def test_finite_strain_laws_linearise_to_hooke(law):
    """At H = 0 every finite-strain plane strain law has zero stress and Hooke's tangent (small-strain limit)."""
    H = sp.Matrix(2, 2, sp.symbols("h0:4", real=True))
    E, nu = sp.Rational(3), sp.Rational(1, 4)
    W = law(H, E, nu, "strain")
    C = hooke(E, nu, "strain")
    at0 = {h: 0 for h in H}
    flat = [(0, 0), (0, 1), (1, 0), (1, 1)]
    for a, (i, j) in enumerate(flat):
        assert sp.simplify(sp.diff(W, H[i, j]).subs(at0)) == 0
        for b, (k, l) in enumerate(flat):
            assert sp.simplify(sp.diff(W, H[i, j], H[k, l]).subs(at0) - C(i, j, k, l)) == 0


def test_incompressible_neo_hookean_sheet_in_equibiaxial_stretch():
    """Plane stress neo-Hookean sheet, F = diag(l, l): W = mu/2 (2 l^2 + l^-4 - 3), the membrane's closed form."""
    lam = sp.Symbol("l", positive=True)
    E = sp.Symbol("E", positive=True)
    H = sp.Matrix([[lam - 1, 0], [0, lam - 1]])
    W = neo_hookean(H, E, sp.Rational(1, 2), "stress")
    assert sp.simplify(W - E / 6 * (2 * lam**2 + lam**-4 - 3)) == 0


def test_edge_terms_get_the_outward_normal_and_values_only():
    m = Model("plane_edge_test")
    m.params(Param("P", 2.0, "Pa"), Param("Lx", 1.0, "m", positive=True), Param("Ly", 1.0, "m", positive=True),
             Param("E", 1.0, "Pa", positive=True))
    m.plane("ux", "uy", domain=rectangle("Lx", "Ly"), group="u")

    @m.potential_density
    def potential(u, p):
        return linear_elastic(gradient(u, "ux", "uy"), p.E, sp.Rational(1, 4), "strain")

    @m.edge_potential("top")
    def pressure(u, p, n):
        return p.P * (n.x * u.ux + n.y * u.uy)

    eqs = derive_plane(m, all_free(m))
    jets, local = eqs.edges["top"]
    assert jets == (("ux", ""), ("uy", ""))
    P = [s for s in local.params if s.name == "P"][0]
    assert list(local.residual) == [P * NORMAL[0], P * NORMAL[1]] and local.position == (X, Y, *NORMAL)

    @m.edge_potential("left")
    def bad(u, p):
        return u.ux_x

    with pytest.raises(ModelError, match="uses a derivative"):
        derive_plane(m, all_free(m))


def test_bad_declarations_are_refused():
    m = Model("plane_bad")
    m.params(Param("R", 1.0, "m", positive=True))
    with pytest.raises(ModelError, match="not a plane domain"):
        m.plane("ux", domain="disk")
    m.plane("w", domain=disk("R"))
    with pytest.raises(ModelError, match="already declares"):
        m.plane("v", domain=disk("R"))
    with pytest.raises(ModelError, match="not a boundary"):
        m.edge_potential("top")

    @m.potential_density
    def potential(u, p):
        return u.w_x**2 + u.w_y**2

    @m.boundary
    def boundary():
        return [fix("w", "rim")]

    with pytest.raises(ModelError, match="outer"):
        derive_plane(m, all_free(m))
    assert plane_jet("w_xt", ("w",)) == ("w", "x", 1) and plane_jet("w_xy", ("w",)) is None


def test_mooney_rivlin_sheet_and_small_strain_limit():
    """Incompressible sheet, equibiaxial stretch l: W = C1 (2 l^2 + l^-4 - 3) + C2 (2 l^-2 + l^4 - 3) (Treloar's
    sheet); plane strain at H = 0: zero stress and Hooke's tangent with mu = 2 (C1 + C2), lambda = K - 2 mu / 3."""
    from mechgen.symbolic.plane_materials import mooney_rivlin

    lam, C1, C2 = sp.symbols("l C1 C2", positive=True)
    H = sp.Matrix([[lam - 1, 0], [0, lam - 1]])
    W = mooney_rivlin(H, C1, C2, "stress")
    assert sp.simplify(W - (C1 * (2 * lam**2 + lam**-4 - 3) + C2 * (2 * lam**-2 + lam**4 - 3))) == 0
    Hs = sp.Matrix(2, 2, sp.symbols("h0:4", real=True))
    c1, c2, K = sp.Rational(1, 3), sp.Rational(1, 5), sp.Rational(7, 2)
    W = mooney_rivlin(Hs, c1, c2, "strain", bulk=K)
    mu = 2 * (c1 + c2)
    lame = K - 2 * mu / 3
    d = lambda i, j: 1 if i == j else 0  # noqa: E731
    C = lambda i, j, k, l: lame * d(i, j) * d(k, l) + mu * (d(i, k) * d(j, l) + d(i, l) * d(j, k))  # noqa: E731
    at0 = {h: 0 for h in Hs}
    flat = [(0, 0), (0, 1), (1, 0), (1, 1)]
    for i, j in flat:
        assert sp.simplify(sp.diff(W, Hs[i, j]).subs(at0)) == 0
        for k, l in flat:
            assert sp.simplify(sp.diff(W, Hs[i, j], Hs[k, l]).subs(at0) - C(i, j, k, l)) == 0
    with pytest.raises(ModelError, match="bulk"):
        mooney_rivlin(Hs, c1, c2, "strain")
