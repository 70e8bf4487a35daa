"""derive: Lagrange residuals and linear matrices against equations derived by hand."""
import sympy as sp

from mechgen import models
from mechgen.symbolic.derive import derive_lumped
from mechgen.symbolic.lattice import derive_lattice
from mechgen.symbolic.specialize import all_free, specialize


def test_spring_pendulum_residual_matches_hand_derivation():
    """Polar elastic pendulum (e.g. Goldstein, Classical Mechanics, sec. 1.6):
    m (r'' - r theta'^2) + k (r - l0) - m g cos(theta) = 0,
    m (r^2 theta'' + 2 r r' theta') + m g r sin(theta) = 0."""
    eqs = derive_lumped(models.get("spring_pendulum"), all_free(models.get("spring_pendulum")))
    r, th = eqs.q
    rd, thd = eqs.v
    rdd, thdd = eqs.a
    m, k, l0, g = sp.symbols("m k l0 g", real=True, positive=True)
    g = sp.Symbol("g", real=True)
    subs = {s: sp.Symbol(s.name, real=True) for s in eqs.params}
    hand = [m * (rdd - r * thd**2) + k * (r - l0) - m * g * sp.cos(th),
            m * (r**2 * thdd + 2 * r * rd * thd) + m * g * r * sp.sin(th)]
    hand = [h.subs({m: subs[eqs.params[0]], k: subs[eqs.params[1]], l0: subs[eqs.params[2]]}) for h in hand]
    for derived, expected in zip(eqs.residual, hand):
        assert sp.simplify(derived.subs(subs) - expected) == 0


def test_laval_linear_matrices():
    """Linearised Laval rotor: M = diag(m, m, Id, Id), G = Ip Omega [[0, 1], [-1, 0]] on the tilts,
    K = diag(k_t, k_t, k_r, k_r) + c_i Omega [[0, 1], [-1, 0]] on the translations (the circulatory matrix of
    internal damping), D = diag(c + c_i, c + c_i, c_r, c_r) (Genta, Dynamics of Rotating Systems, ch. 4 and
    sec. 8.3)."""
    model = models.get("laval_rotor")
    eqs = derive_lumped(model, all_free(model))
    p = {s.name: s for s in eqs.params}
    rest = {s: 0 for s in eqs.q + eqs.v}
    mats = {k: sp.simplify(v.subs(rest)) for k, v in eqs.linear_matrices().items()}
    assert mats["M"] == sp.diag(p["m"], p["m"], p["Id"], p["Id"])
    circulatory = sp.zeros(4, 4)
    circulatory[0, 1], circulatory[1, 0] = p["c_i"] * p["Omega"], -p["c_i"] * p["Omega"]
    assert sp.simplify(mats["K"] - sp.diag(p["k_t"], p["k_t"], p["k_r"], p["k_r"]) - circulatory) == sp.zeros(4, 4)
    assert sp.simplify(mats["D"] - sp.diag(p["c"] + p["c_i"], p["c"] + p["c_i"], p["c_r"], p["c_r"])) == sp.zeros(4, 4)
    G = sp.zeros(4, 4)
    G[2, 3], G[3, 2] = p["Ip"] * p["Omega"], -p["Ip"] * p["Omega"]
    assert mats["G"] == G


def test_fixed_zero_parameter_removes_terms():
    """A parameter fixed at 0 by a scene is folded before deriving: damping disappears."""
    model = models.get("laval_rotor")
    eqs = derive_lumped(model, specialize(model, {"c": 0.0, "c_r": 0.0}, free=("Omega",)))
    rest = {s: 0 for s in eqs.q + eqs.v}
    assert eqs.linear_matrices()["D"].subs(rest) == sp.zeros(4, 4)
    assert all(sp.Symbol(n, real=True) not in eqs.residual.free_symbols for n in ("c", "c_r"))
    assert all(s.name == "Omega" for s in eqs.params)


def test_active_coordinates_freeze_the_rest():
    """Only the tilts active: a 2-DOF gyroscopic system."""
    model = models.get("laval_rotor")
    eqs = derive_lumped(model, specialize(model, {}, free=("Omega",), active=("theta_x", "theta_y")))
    assert eqs.coordinates == ("theta_x", "theta_y")
    assert eqs.linear_matrices()["M"].shape == (2, 2)


def test_fpu_local_pieces():
    """Bond force of the FPU chain is f(r) = gamma r + alpha r^2 + beta r^3 (seed 003, eq. 1.2-1.3)."""
    model = models.get("fpu_chain")
    eqs = derive_lattice(model, all_free(model))
    ua, ub = eqs.bond_q
    gamma, alpha, beta = eqs.params
    r = ub - ua
    assert sp.expand(eqs.bond_gradient()[1] - (gamma * r + alpha * r**2 + beta * r**3)) == 0
    assert sp.expand(eqs.bond_gradient()[0] + eqs.bond_gradient()[1]) == 0
    assert eqs.site_residual == eqs.site_a
