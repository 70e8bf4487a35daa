"""``mechgen bench multibody``: the n-link planar pendulum, the scaling problem of symbolic multibody tools.

n rigid massless links of length l, a point mass m at the end of each, angles theta_i from the downward
vertical, written as a user writes it (:func:`pendulum_model`): with x_k = l sum_{i<=k} sin(theta_i),
y_k = -l sum_{i<=k} cos(theta_i),

    T = m/2 sum_k (x_k'^2 + y_k'^2),      V = m g sum_k y_k        (SI units).

Its equations of motion in closed form (the independent reference of the tests) are

    sum_j m l^2 c_ij [cos(theta_i - theta_j) a_j + sin(theta_i - theta_j) w_j^2] + m g l (n - i) sin(theta_i) = 0,

c_ij = n - max(i, j) the number of masses beyond both links (0-based i, j).
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param


def pendulum_model(n: int) -> Model:
    """The n-link planar pendulum as a mechgen model ``pendulum<n>`` (coordinates theta0 ... theta<n-1>)."""
    model = Model(f"pendulum{n}", doc=f"{n}-link planar pendulum, point masses at the link ends")
    model.params(Param("m", 1.0, "kg", "mass at each link end", positive=True),
                 Param("l", 1.0, "m", "link length", positive=True),
                 Param("g", 9.81, "m/s^2", "gravity"))
    names = [f"theta{i}" for i in range(n)]
    model.coordinates(*names)

    @model.kinetic
    def kinetic(q, v, p):
        xd = yd = T = 0
        for name in names:
            xd += p.l * sp.cos(q[name]) * v[name]
            yd += p.l * sp.sin(q[name]) * v[name]
            T += p.m / 2 * (xd**2 + yd**2)
        return T

    @model.potential
    def potential(q, p):
        y = V = 0
        for name in names:
            y -= p.l * sp.cos(q[name])
            V += p.m * p.g * y
        return V

    return model


def lattice_model(rows: int, cols: int) -> Model:
    """A planar mass-spring lattice ``lattice<rows>x<cols>`` as ONE lumped mechgen model.

    rows x cols point masses m on a square grid of spacing a (node (i, j) at rest at x = a j, y = -a i); the left
    column (j = 0) is anchored, every other node moves in the plane with displacements (ux_i_j, uy_i_j) (2 rows
    (cols - 1) coordinates). Nonlinear springs join the 4-neighbours:

        T = m/2 sum (ux'^2 + uy'^2),   V = sum_springs k/2 (|r_a - r_b| - a)^2 + m g sum y     (SI units),

    with r the node's position (rest position plus displacement).
    """
    model = Model(f"lattice{rows}x{cols}", doc=f"{rows} x {cols} planar mass-spring lattice, left column anchored")
    model.params(Param("m", 1.0, "kg", "mass of each node", positive=True),
                 Param("k", 100.0, "N/m", "spring stiffness", positive=True),
                 Param("a", 1.0, "m", "spring rest length and grid spacing", positive=True),
                 Param("g", 9.81, "m/s^2", "gravity"))
    nodes = lattice_nodes(rows, cols)
    model.coordinates(*[f"u{ax}_{i}_{j}" for i, j in nodes for ax in "xy"])

    @model.kinetic
    def kinetic(q, v, p):
        return sum(p.m / 2 * (v[f"ux_{i}_{j}"]**2 + v[f"uy_{i}_{j}"]**2) for i, j in nodes)

    @model.potential
    def potential(q, p):
        def position(i, j):
            if j == 0:
                return p.a * j, -p.a * i
            return p.a * j + q[f"ux_{i}_{j}"], -p.a * i + q[f"uy_{i}_{j}"]
        V = sum(p.m * p.g * position(i, j)[1] for i, j in nodes)
        for (i, j), (k, l) in lattice_springs(rows, cols):
            (xa, ya), (xb, yb) = position(i, j), position(k, l)
            V += p.k / 2 * (sp.sqrt((xa - xb)**2 + (ya - yb)**2) - p.a)**2
        return V

    return model


def lattice_nodes(rows: int, cols: int) -> list[tuple[int, int]]:
    """The moving nodes (i, j) of the lattice, row by row (the order of the coordinates ux, uy of each)."""
    return [(i, j) for i in range(rows) for j in range(1, cols)]


def lattice_springs(rows: int, cols: int) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """Every 4-neighbour pair of nodes with at least one moving node (springs between anchored nodes do not
    matter)."""
    out = [((i, j), (i, j + 1)) for i in range(rows) for j in range(cols - 1)]
    out += [((i, j), (i + 1, j)) for i in range(rows - 1) for j in range(1, cols)]
    return out


# -- the same systems in PyDy / sympy.physics.mechanics ---------------------------------------------------------
def pydy_pendulum(n: int, method: str = "kane") -> dict:
    """The n-link pendulum in sympy.physics.mechanics as PyDy's examples write it: frames A_i rotated by q_i about
    N.z, P_i = P_{i-1} - l A_i.y, particles of mass m, gravity -m g N.y; Kane's method (u_i = q_i') or
    LagrangesMethod on L = T - V (q_i' renamed u_i afterwards). {"M", "F", "q", "u", "constants", "values"} with
    M u' = F (n x n, n)."""
    import sympy.physics.mechanics as me

    q, u = me.dynamicsymbols(f"q:{n}"), me.dynamicsymbols(f"u:{n}")
    m, l, g = sp.symbols("m l g")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    point, particles = O, []
    for i in range(n):
        frame = N.orientnew(f"A{i}", "Axis", [q[i], N.z])
        frame.set_ang_vel(N, (u[i] if method == "kane" else q[i].diff()) * N.z)
        point = point.locatenew(f"P{i}", -l * frame.y)
        point.v2pt_theory(O if i == 0 else previous, N, frame)
        particles.append(me.Particle(f"pa{i}", point, m))
        previous = point
    return _pydy_equations(method, N, q, u, particles, [(pa.point, -m * g * N.y) for pa in particles],
                           (m, l, g), (1.0, 1.0, 9.81), lambda pa: m * g * pa.point.pos_from(O).dot(N.y))


def pydy_lattice(rows: int, cols: int, method: str = "kane") -> dict:
    """:func:`lattice_model` in sympy.physics.mechanics: a particle per moving node located by its displacement
    (coordinates in :func:`lattice_nodes` order, x then y), spring forces along each 4-neighbour pair
    (-k (|d| - a) d/|d| on one end, the opposite on the other) and gravity. Same return as :func:`pydy_pendulum`."""
    import sympy.physics.mechanics as me

    nodes = lattice_nodes(rows, cols)
    q, u = me.dynamicsymbols(f"q:{2 * len(nodes)}"), me.dynamicsymbols(f"u:{2 * len(nodes)}")
    m, k, a, g = sp.symbols("m k a g")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    points, particles = {}, []
    for idx, (i, j) in enumerate(nodes):
        P = O.locatenew(f"P{i}_{j}", (a * j + q[2 * idx]) * N.x + (-a * i + q[2 * idx + 1]) * N.y)
        P.set_vel(N, (u[2 * idx] if method == "kane" else q[2 * idx].diff()) * N.x
                  + (u[2 * idx + 1] if method == "kane" else q[2 * idx + 1].diff()) * N.y)
        points[i, j] = P
        particles.append(me.Particle(f"pa{i}_{j}", P, m))
    for i in range(rows):
        points[i, 0] = O.locatenew(f"W{i}", -a * i * N.y)
    loads = [(pa.point, -m * g * N.y) for pa in particles]
    springs = []
    for A, B in lattice_springs(rows, cols):
        d = points[A].pos_from(points[B])
        length = sp.sqrt(d.dot(d))
        springs.append(k / 2 * (length - a)**2)
        force = -k * (length - a) / length * d
        loads += [(points[A], force)] + ([(points[B], -force)] if B[1] > 0 else [])
    return _pydy_equations(method, N, q, u, particles, loads, (m, k, a, g), (1.0, 100.0, 1.0, 9.81),
                           lambda pa: m * g * pa.point.pos_from(O).dot(N.y), extra_potential=sum(springs))


def _pydy_equations(method, N, q, u, particles, loads, constants, values, potential, extra_potential=0) -> dict:
    """Kane's method with the given loads, or LagrangesMethod on T - V (V: ``potential`` of each particle plus
    ``extra_potential``), as M u' = F."""
    import sympy.physics.mechanics as me

    if method == "kane":
        kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)])
        kane.kanes_equations(particles, loads)
        M, F = kane.mass_matrix, kane.forcing
    else:
        V = sum(potential(pa) for pa in particles) + extra_potential
        lagrange = me.LagrangesMethod(me.Lagrangian(N, *particles) - V, q)
        lagrange.form_lagranges_equations()
        rename = {qi.diff(): ui for qi, ui in zip(q, u)}
        M, F = me.msubs(lagrange.mass_matrix, rename), me.msubs(lagrange.forcing, rename)
    return {"M": M, "F": F, "q": q, "u": u, "constants": list(constants), "values": np.array(values)}


def pydy_rhs(eqs: dict, generator: str):
    """PyDy's generated right-hand side ``f(t, x) -> x'`` (x = q, u) of M u' = F, q' = u (generate_ode_function,
    ``generator`` "lambdify" or "cython", linear solve by numpy)."""
    from pydy.codegen.ode_function_generators import generate_ode_function

    rhs = generate_ode_function(eqs["F"], eqs["q"], eqs["u"], eqs["constants"], mass_matrix=eqs["M"],
                                coordinate_derivatives=sp.Matrix(eqs["u"]), generator=generator)
    values = eqs["values"]
    return lambda t, x: rhs(x, t, values)
