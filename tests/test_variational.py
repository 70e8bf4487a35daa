"""Structure-preserving integration for any Lagrangian (issue 25, item 4).

1. The splittings (``simulate``'s ``method = "leapfrog"``, the ``symplectic`` kind) integrate
   q'' = M^-1 (-dV/dq) with a constant diagonal M and nothing else; a model whose derived equations are not
   that (the triple pendulum below: M depends on the angles) is refused at ``method`` (exit 2), while a chain
   (T = u'^2 / 2 per site) still runs.
2. ``method = "variational"`` (mechgen.runtime.core.variational), against independent references:
   * its order (2 for the midpoint, 2 s for Gauss-Legendre of s stages) from a convergence study against scipy's
     DOP853 at rtol 1e-12 on the hand-derived equations of a spring pendulum with a dashpot and a harmonic torque
     (configuration-dependent mass, Rayleigh dissipation, a time-dependent force):
         m r'' = m r th'^2 - k (r - l0) + m g cos(th) - c r',
         m r^2 th'' = -2 m r r' th' - m g r sin(th) + A cos(w t);
   * a momentum its symmetry gives, to round-off: a free rotor's p_phi = m r^2 phi' (phi cyclic), and a particle
     in a central potential in Cartesian coordinates, whose angular momentum x p_y - y p_x is kept by the discrete
     Noether theorem (the midpoint and Gauss discrete Lagrangians are invariant under rotations);
   * the energy of a damped oscillator m x'' + c x' + k x = 0 against its closed form
         x(t) = e^(-zeta w t) (x0 cos(w_d t) + zeta w x0 / w_d sin(w_d t)), E = m x'^2 / 2 + k x^2 / 2,
     converging at the method's order;
   * the energy error of the triple pendulum's large swing bounded (no drift) over long runs;
   * refusals (a hybrid model, internal variables, a chain, a missing or too large dt, unknown stages): exit 2.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError
from mechgen.runtime.core.variational import run_variational

TRIPLE = '''"""Triple pendulum: three point masses m on rigid massless rods of length l, angles from the downward vertical.

x_i = l sum_{j<=i} sin(th_j), y_i = -l sum_{j<=i} cos(th_j); T = sum m/2 (x_i'^2 + y_i'^2), V = sum m g y_i.
"""
import sympy as sp

from mechgen import Model, Param

model = Model("triple_pendulum", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("l", 1.0, "m"), Param("g", 1.0, "m/s^2"))
model.coordinates("th1", "th2", "th3")


def points(q, v, p):
    x = y = vx = vy = 0
    out = []
    for a, w in ((q.th1, v.th1), (q.th2, v.th2), (q.th3, v.th3)):
        x, y = x + p.l * sp.sin(a), y - p.l * sp.cos(a)
        vx, vy = vx + p.l * sp.cos(a) * w, vy + p.l * sp.sin(a) * w
        out.append((x, y, vx, vy))
    return out


@model.kinetic
def kinetic(q, v, p):
    return sum(p.m / 2 * (vx**2 + vy**2) for _, _, vx, vy in points(q, v, p))


@model.potential
def potential(q, v, p):
    return sum(p.m * p.g * y for _, y, _, _ in points(q, v, p))
'''


SOFT_CHAIN = '''"""A chain whose site mass grows with the displacement: T_s = (1 + u^2) u'^2 / 2, V_b = (u_b - u_a)^2 / 2."""
from mechgen import Model, Param

model = Model("soft_chain", doc=__doc__)
model.params(Param("N", 6, "", "sites", size=True))
model.chain("u", sites="N", ends="fixed")


@model.site_kinetic
def site_kinetic(s):
    return (1 + s.q**2) * s.v**2 / 2


@model.bond_potential
def bond_potential(a, b):
    return (b.q - a.q) ** 2 / 2
'''


SWING = '''"""A spring pendulum with a dashpot on the spring and a harmonic torque at the pivot (polar r, theta)."""
import sympy as sp

from mechgen import Model, Param

model = Model("driven_spring_pendulum", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("k", 20.0, "N/m"), Param("l0", 1.0, "m"), Param("g", 9.81, "m/s^2"),
             Param("c", 0.3, "N s/m"), Param("A", 0.5, "N m"), Param("w", 2.0, "rad/s"))
model.coordinates("r", "theta")
model.output("radius", lambda q: q.r)
model.output("angle", lambda q: q.theta)


@model.kinetic
def kinetic(q, v, p):
    return p.m / 2 * (v.r**2 + q.r**2 * v.theta**2)


@model.potential
def potential(q, p):
    return p.k / 2 * (q.r - p.l0) ** 2 - p.m * p.g * q.r * sp.cos(q.theta)


@model.dissipation
def dashpot(v, p):
    return p.c / 2 * v.r**2


@model.forces
def torque(t, p):
    return {"theta": p.A * sp.cos(p.w * t)}
'''

ROTOR = '''"""Two masses on a spring spinning freely in a plane: relative distance r, angle phi (cyclic), reduced mass m."""
from mechgen import Model, Param

model = Model("free_rotor", doc=__doc__)
model.params(Param("m", 0.5, "kg"), Param("k", 30.0, "N/m"), Param("l0", 1.0, "m"))
model.coordinates("r", "phi")
model.output("p_phi", lambda q, v, p: p.m * q.r**2 * v.phi)


@model.kinetic
def kinetic(q, v, p):
    return p.m / 2 * (v.r**2 + q.r**2 * v.phi**2)


@model.potential
def potential(q, p):
    return p.k / 2 * (q.r - p.l0) ** 2
'''

CENTRAL = '''"""A particle in the plane in the central potential V = k (x^2 + y^2)^2 / 4 - a sqrt(1 + x^2 + y^2)."""
import sympy as sp

from mechgen import Model, Param

model = Model("central_particle", doc=__doc__)
model.params(Param("m", 1.3, "kg"), Param("k", 2.0, "N/m^3"), Param("a", 1.5, "J"))
model.coordinates("x", "y")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * (v.x**2 + v.y**2)


@model.potential
def potential(q, p):
    rr = q.x**2 + q.y**2
    return p.k * rr**2 / 4 - p.a * sp.sqrt(1 + rr)
'''

OSCILLATOR = '''"""m x'' + c x' + k x = 0"""
from mechgen import Model, Param

model = Model("damped_oscillator", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("k", 4.0, "N/m"), Param("c", 0.4, "N s/m"))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.potential
def potential(q, p):
    return p.k / 2 * q.x**2


@model.dissipation
def dashpot(v, p):
    return p.c / 2 * v.x**2
'''

SLS = '''"""mass on a standard linear solid: m x'' + k1 x + k2 (x - s) = 0, c s' = k2 (x - s)"""
from mechgen import Model, Param

model = Model("sls_oscillator", doc=__doc__)
model.params(Param("m", 2.0, "kg"), Param("k1", 3.0, "N/m"), Param("k2", 5.0, "N/m"), Param("c", 0.7, "N s/m"))
model.coordinates("x")
model.internal("s", rate=lambda q, z, p: p.k2 * (q.x - z.s) / p.c)


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.potential
def potential(q, z, p):
    return p.k1 / 2 * q.x**2 + p.k2 / 2 * (q.x - z.s) ** 2
'''

ROTATING = '''"""A particle in a frame spinning at Omega about z: T has terms linear in the velocity (Coriolis)."""
from mechgen import Model, Param

model = Model("rotating_particle", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("W", 0.7, "rad/s"), Param("k", 3.0, "N/m^3"))
model.coordinates("x", "y")


@model.kinetic
def kinetic(q, v, p):
    return p.m / 2 * ((v.x - p.W * q.y) ** 2 + (v.y + p.W * q.x) ** 2)


@model.potential
def potential(q, p):
    return p.k / 4 * (q.x**4 + 2 * q.y**4) + q.x**2 / 2
'''

MODELS = {"rotating": ROTATING, "triple": TRIPLE, "soft_chain": SOFT_CHAIN, "swing": SWING, "rotor": ROTOR, "central": CENTRAL,
          "oscillator": OSCILLATOR, "sls": SLS}
#: the lowest linear period 2 pi / omega_1 of the triple pendulum (m = l = g = 1): omega_1^2 = 0.41577... g / l,
#: the smallest root of w^6 - 9 w^4 + 18 w^2 - 6 = 0 (the eigenvalues of M^-1 K at rest, in units of g / l)
TRIPLE_T1 = 2 * math.pi / math.sqrt(0.4157745568)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("variational_models")
    for name, text in MODELS.items():
        (path / f"{name}.py").write_text(text)
    return path


@pytest.fixture(scope="module")
def triple(folder):
    return mechgen.compile(str(folder / "triple.py"), backend="c", kernels=["lagrangian", "outputs"])


def run_here(path, text: str, capsys) -> tuple[int, str, str]:
    """``mechgen run`` of a scene in this process (the CLI's main): exit code, stdout, stderr."""
    path.write_text(text)
    code = main(["run", str(path)])
    out = capsys.readouterr()
    return code, out.out, out.err


# --------------------------------------------------------------------------- 1. the splittings' refusal

def test_leapfrog_refuses_the_triple_pendulum_at_method(folder, tmp_path, capsys):
    """M(q) of the triple pendulum depends on the angles: the leapfrog's division by diag(M(0)) would be wrong,
    so the scene ends with exit 2 at 'method', naming why and the methods to use instead."""
    scene = (f'model = "{folder / "triple.py"}"\n[[analysis]]\nname = "swing"\nkind = "simulate"\nt_end = 1.0\n'
             'method = "leapfrog"\ndt = 0.01\nq0 = { th1 = 1.0 }\n')
    code, _, err = run_here(tmp_path / "leap.toml", scene, capsys)
    assert code == 2, err
    assert "'method'" in err and "depends on th1, th2, th3" in err
    assert "variational" in err and "Traceback" not in err
    system = mechgen.compile(str(folder / "triple.py"), backend="numpy", kernels=["force", "outputs", "linear"])
    with pytest.raises(InputError) as info:
        mechgen.simulate(system, t_end=1.0, method="leapfrog", dt=0.01)
    assert info.value.key == "method" and "mass matrix" in str(info.value)


def test_the_symplectic_kind_and_the_leapfrog_still_run_a_chain():
    """The FPU chain (T_s = u'^2 / 2, V_b(r)) is what the splittings are for: both still run, and the
    leapfrog's energy error at dt = 0.01 over t = 1 stays at its O(dt^2) level."""
    chain = mechgen.compile("fpu_chain", {"N": 8}, backend="numpy")
    assert chain.kernels["force"].spec["meta"]["separable"] is True
    out = mechgen.simulate(chain, t_end=1.0, method="leapfrog", dt=0.01, initial_mode=1).outputs
    assert out["energy_drift"] < 1e-4  # leapfrog: |E - E0| / E0 ~ (omega dt)^2 / 8 with omega < 2
    sym = mechgen.symplectic(chain, integrator="yoshida4", dt=0.05, t_end=10.0).outputs
    assert sym["energy_error"] < 1e-5  # order 4 at omega dt < 0.1


def test_the_symplectic_kind_refuses_a_chain_whose_site_mass_moves(folder):
    """A chain with T_s = (1 + u^2) u'^2 / 2 has a configuration-dependent mass: refused at 'integrator'."""
    chain = mechgen.compile(str(folder / "soft_chain.py"), backend="numpy")
    with pytest.raises(InputError) as info:
        mechgen.symplectic(chain, integrator="leapfrog", dt=0.05, t_end=1.0)
    assert info.value.key == "integrator" and "site mass matrix d2T/dv2 depends on u" in str(info.value)


# --------------------------------------------------------------------------- 2. the variational integrator

def swing_reference(t_end: float, y0) -> np.ndarray:
    """(r, th, r', th') at t_end from the hand-derived equations (module doc), DOP853 at rtol 1e-12."""
    m, k, l0, g, c, A, w = 1.0, 20.0, 1.0, 9.81, 0.3, 0.5, 2.0

    def rhs(t, y):
        r, th, rd, thd = y
        rdd = r * thd**2 - k / m * (r - l0) + g * np.cos(th) - c / m * rd
        thdd = (-2 * m * r * rd * thd - m * g * r * np.sin(th) + A * np.cos(w * t)) / (m * r**2)
        return [rd, thd, rdd, thdd]

    return solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]


@pytest.mark.parametrize("stages, steps", [(1, [0.04, 0.02, 0.01, 0.005]), (2, [0.1, 0.05, 0.025, 0.0125]),
                                           (3, [0.2, 0.1, 0.05])])
def test_order_of_convergence_against_the_hand_derived_equations(folder, stages, steps):
    """The error at t = 2 against DOP853 falls as dt^(2 s): the fitted slope of log error on log dt is 2 s
    (measured 2.00, 3.99, 6.1; the smallest error, 6e-9 for s = 3, is 600 times the reference's 1e-11)."""
    system = mechgen.compile(str(folder / "swing.py"), backend="c")
    ref = swing_reference(2.0, [1.3, 1.0, 0.0, 0.5])
    errors = []
    for dt in steps:
        out = mechgen.simulate(system, t_end=2.0, method="variational", dt=dt, stages=stages,
                               q0={"r": 1.3, "theta": 1.0}, v0={"theta": 0.5}).outputs
        errors.append(max(abs(out["radius"] - ref[0]), abs(out["angle"] - ref[1])))
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    print(f"variational, {stages} stage(s): errors {['%.2e' % e for e in errors]}, order {slope:.3f}")
    # an asymptotic C dt^p error: the slope is p up to the next term's share (a few percent at these steps)
    assert abs(slope - 2 * stages) < 0.25


def test_free_rotor_keeps_its_cyclic_momentum_to_round_off(folder):
    """phi is cyclic: p_phi = m r^2 phi' is constant. Over 20 000 midpoint steps of a rotor whose spring swings
    (r between 1 and about 1.11), the sampled p_phi equals its start to 1e-13 relative (round-off of the samples' v)."""
    system = mechgen.compile(str(folder / "rotor.py"), backend="c", kernels=["lagrangian", "outputs"])
    run = run_variational(system, [1.0, 0.0], [0.0, 2.0], 200.0, 0.01, save_every=100)
    p_phi = 0.5 * run.q[:, 0] ** 2 * run.v[:, 1]
    drift = float(np.max(np.abs(p_phi / p_phi[0] - 1.0)))
    print(f"free rotor: max relative change of p_phi {drift:.2e} over {run.steps} steps")
    assert np.ptp(run.q[:, 0]) > 0.1 and drift < 1e-13  # the spring does swing; a few ulps of v per sample


@pytest.mark.parametrize("stages", [1, 2])
def test_central_force_keeps_angular_momentum_by_discrete_noether(folder, stages):
    """x p_y - y p_x of a particle in a central potential (Cartesian coordinates, so no coordinate is cyclic) is
    kept by the discrete flow to round-off, 1e-12 relative over 10 000 steps, while its energy error is ~1e-4."""
    system = mechgen.compile(str(folder / "central.py"), backend="c", kernels=["lagrangian", "outputs"])
    energy = lambda q, v, t: system.outputs(q, v, t=t)["energy"]  # noqa: E731
    run = run_variational(system, [1.2, 0.0], [0.1, 0.9], 200.0, 0.02, stages=stages, save_every=10, energy=energy)
    L = run.q[:, 0] * run.p[:, 1] - run.q[:, 1] * run.p[:, 0]
    drift = float(np.max(np.abs(L / L[0] - 1.0)))
    print(f"central force, {stages} stage(s): angular momentum {drift:.2e}, energy {np.ptp(run.energy):.2e}")
    assert drift < 1e-12  # Newton stops at 1e-13 of |V|; 10^4 steps of round-off stay below this
    assert np.ptp(run.q[:, 0] ** 2 + run.q[:, 1] ** 2) > 0.1  # a real orbit, not a circle


@pytest.mark.parametrize("stages, steps", [(1, [0.1, 0.05, 0.025]), (2, [0.2, 0.1, 0.05])])
def test_damped_energy_decay_meets_the_closed_form_at_the_methods_order(folder, stages, steps):
    """E(t = 10) of m x'' + c x' + k x = 0 (zeta = 0.1) against the closed form, and the dissipated energy
    E(0) - E(10): both errors fall as dt^(2 s)."""
    system = mechgen.compile(str(folder / "oscillator.py"), backend="c",
                             kernels=["lagrangian", "outputs", "energy_rates"])
    m, k, c, x0, t = 1.0, 4.0, 0.4, 1.0, 10.0
    w, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
    wd = w * math.sqrt(1 - zeta**2)
    x = math.exp(-zeta * w * t) * (x0 * math.cos(wd * t) + zeta * w * x0 / wd * math.sin(wd * t))
    v = -math.exp(-zeta * w * t) * x0 * w**2 / wd * math.sin(wd * t)
    exact = m * v**2 / 2 + k * x**2 / 2
    runs = [mechgen.simulate(system, t_end=t, method="variational", dt=dt, stages=stages, q0={"x": x0}).outputs
            for dt in steps]
    errors = [abs(out["energy"] - exact) for out in runs]
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    # the dissipated energy, integrated by the step's own quadrature, is E(0) - E(10) of the closed form
    lost = [abs(out["dissipated"] - (k * x0**2 / 2 - exact)) for out in runs]
    lost_slope = np.polyfit(np.log(steps), np.log(lost), 1)[0]
    print(f"damped oscillator, {stages} stage(s): E(10) = {exact:.6g}, errors {['%.2e' % e for e in errors]}, "
          f"order {slope:.3f}; dissipated errors {['%.2e' % e for e in lost]}, order {lost_slope:.3f}; "
          f"balance error {['%.1e' % out['energy_balance_error'] for out in runs]}")
    assert abs(slope - 2 * stages) < 0.3  # asymptotic C dt^p (the same allowance as the order study)
    assert abs(lost_slope - 2 * stages) < 0.3
    assert "energy_drift" not in runs[0]  # a dissipative run reports its balance instead


def test_compiled_and_python_loops_agree(triple, folder):
    """The C loop (variational_loop.c) and the Python stepper keep one set of rules: the same samples to
    rounding (1e-12 after 500 Gauss steps of a large swing; LU here, LAPACK there), and for the driven, damped
    swing the same integrals of the energy balance (work, dissipated)."""
    runs = {loop: run_variational(triple, [1.5, 1.0, 0.5], [0.0, 0.0, 0.0], 5.0, 0.01, stages=2, save_every=50,
                                  loop=loop) for loop in ("c", "python")}
    assert runs["c"].loop == "c" and runs["python"].loop == "python"
    assert np.max(np.abs(runs["c"].q - runs["python"].q)) < 1e-12
    assert np.max(np.abs(runs["c"].v - runs["python"].v)) < 1e-12
    swing = mechgen.compile(str(folder / "swing.py"), backend="c", kernels=["lagrangian", "outputs", "energy_rates"])
    runs = {loop: run_variational(swing, [1.3, 1.0], [0.0, 0.5], 3.0, 0.01, stages=3, save_every=30, balance=True,
                                  loop=loop) for loop in ("c", "python")}
    assert np.max(np.abs(runs["c"].q - runs["python"].q)) < 1e-12
    assert np.max(np.abs(runs["c"].w - runs["python"].w)) < 1e-12 and np.all(runs["c"].w[-1, :2] != 0.0)


def triple_energy_run(system, q0, periods: float, dt: float, stages: int, samples: int = 20000):
    """|E - E0| at ``samples`` points of a run of the triple pendulum from rest at q0 over ``periods`` T_1."""
    energy = lambda q, v, t: system.outputs(q, v, t=t)["energy"]  # noqa: E731
    steps = math.ceil(periods * TRIPLE_T1 / dt)
    run = run_variational(system, q0, [0.0, 0.0, 0.0], periods * TRIPLE_T1, dt, stages=stages,
                          save_every=max(1, steps // samples), energy=energy)
    return np.abs(run.energy - run.energy[0])


def test_triple_pendulum_energy_error_stays_bounded(triple):
    """The large swing (all three angles 1 rad from rest, far outside the linear range) over 1000 periods T_1
    (194 887 midpoint steps of dt = 0.05): the largest |E - E0| of each tenth of the run is that of the first to
    10 % (measured: 2.7e-4 in every tenth, within 2 %; a drift would grow tenfold from the first tenth to the last)."""
    err = triple_energy_run(triple, [1.0, 1.0, 1.0], 1000, 0.05, 1)
    tenths = np.array([w.max() for w in np.array_split(err, 10)])
    print(f"triple pendulum, 1000 periods: max |E - E0| per tenth {' '.join('%.3e' % w for w in tenths)}")
    assert np.all(np.abs(tenths / tenths[0] - 1.0) < 0.1)  # bounded: the same bound in every tenth
    assert err.max() < 1e-3  # O(dt^2): (omega dt)^2 / 24 of the swing's energy, about 2e-4 here


@pytest.mark.slow
def test_triple_pendulum_energy_error_stays_bounded_over_1e5_periods(triple):
    """The same swing over 10^5 periods T_1 (9.7 10^6 midpoint steps of dt = 0.1, about 30 s in the C loop):
    every tenth of the run keeps the first tenth's bound to 10 % (no drift over 10^5 periods)."""
    err = triple_energy_run(triple, [1.0, 1.0, 1.0], 100_000, 0.1, 1)
    tenths = np.array([w.max() for w in np.array_split(err, 10)])
    print(f"triple pendulum, 10^5 periods: max |E - E0| per tenth {' '.join('%.3e' % w for w in tenths)}")
    assert np.all(np.abs(tenths / tenths[0] - 1.0) < 0.1)
    assert err.max() < 4e-3  # four times the dt = 0.05 bound (order 2)


def test_chaotic_swing_energy_error_stays_at_the_truncation_level(triple):
    """The chaotic swing (all angles 1.5 rad from rest) over 1000 periods with Gauss-Legendre s = 2, dt = 0.05: the
    energy error stays below 1 % of the energy scale m g l (1 + 2 + 3) = 6 (measured 8.9e-3; measured once over
    10^5 periods, not run here: 0.10, as the chaotic orbit slowly visits states of larger local error)."""
    err = triple_energy_run(triple, [1.5, 1.5, 1.5], 1000, 0.05, 2, samples=10000)
    print(f"chaotic triple pendulum, 1000 periods, s = 2: max |E - E0| = {err.max():.3e}")
    assert err.max() < 0.06


# --------------------------------------------------------------------------- scenes and refusals

SCENE = 'model = "{model}"\n[[analysis]]\nname = "run"\nkind = "simulate"\nt_end = 2.0\nmethod = "variational"\n'


def test_a_scene_runs_variational(folder, tmp_path, capsys):
    code, out, err = run_here(tmp_path / "ok.toml", SCENE.format(model=folder / "swing.py")
                              + 'dt = 0.01\nstages = 2\nq0 = { r = 1.3, theta = 1.0 }\n', capsys)
    assert code == 0, err
    assert "energy_balance_error" in out and "radius" in out  # a driven, damped run: its balance


@pytest.mark.parametrize("model, extra, key, words", [
    ("viscoelastic_impact", "dt = 0.01\n", "method", "has modes"),
    ("{folder}/sls.py", "dt = 0.01\n", "method", "internal variables"),
    ("fpu_chain", "dt = 0.01\n", "method", "is a chain"),
    ("{folder}/swing.py", "", "dt", "needs a time step dt"),
    ("{folder}/swing.py", "dt = 5.0\n", "dt", "exceeds t_end"),
    ("{folder}/swing.py", "dt = -0.1\n", "dt", ""),
    ("{folder}/swing.py", "dt = 0.01\nstages = 4\n", "stages", "not tabulated"),
])
def test_refusals_exit_2_at_the_key(folder, tmp_path, capsys, model, extra, key, words):
    code, _, err = run_here(tmp_path / "bad.toml", SCENE.format(model=model.format(folder=folder)) + extra, capsys)
    assert code == 2, err
    assert f".{key}'" in err and words in err and "Traceback" not in err


def test_stages_belong_to_the_variational_method(folder, tmp_path, capsys):
    text = SCENE.format(model=folder / "swing.py").replace('"variational"', '"Radau"') + "stages = 2\n"
    code, _, err = run_here(tmp_path / "bad.toml", text, capsys)
    assert code == 2 and ".stages'" in err and "method 'variational'" in err


def test_a_newton_failure_names_the_step(triple):
    """A step far too large for the motion (dt = 2 on the large swing) ends with a ConvergenceError naming t and
    dt, never a silent answer."""
    from mechgen.errors import ConvergenceError

    with pytest.raises(ConvergenceError, match="smaller dt"):
        run_variational(triple, [3.0, 3.0, 3.0], [0.0, 5.0, -5.0], 20.0, 2.0)


def test_every_backend_gives_the_same_run(folder):
    """The numpy and CasADi kernels (no C address: the Python stepper) and the C loop agree to 1e-12."""
    ends = []
    for backend in ("c", "numpy", "casadi"):
        system = mechgen.compile(str(folder / "swing.py"), backend=backend, kernels=["lagrangian", "outputs"])
        out = mechgen.simulate(system, t_end=1.0, method="variational", dt=0.01, stages=2,
                               q0={"r": 1.3, "theta": 1.0}).outputs
        ends.append(np.array([out["radius"], out["angle"], out["energy"]]))
    assert np.max(np.abs(ends[1] - ends[0])) < 1e-12 and np.max(np.abs(ends[2] - ends[0])) < 1e-12


def test_a_coordinate_without_inertia_is_named(folder, tmp_path):
    """m = 0 makes dp/dv singular: the run ends with a ConvergenceError saying so (at the start's inverse Legendre
    transform, whichever loop is asked for), not a LinAlgError traceback."""
    from mechgen.errors import ConvergenceError

    system = mechgen.compile(str(folder / "oscillator.py"), {"m": 0.0}, backend="c", kernels=["lagrangian", "outputs"])
    for loop in ("c", "python"):
        with pytest.raises(ConvergenceError, match="singular"):
            run_variational(system, [1.0], [0.0], 1.0, 0.1, loop=loop)


def test_leapfrog_refuses_internal_variables_at_load(folder, tmp_path, capsys):
    """The leapfrog steps no internal variable: a model with one is refused when the scene loads (exit 2)."""
    text = SCENE.format(model=folder / "sls.py").replace('"variational"', '"leapfrog"') + "dt = 0.01\n"
    code, _, err = run_here(tmp_path / "bad.toml", text, capsys)
    assert code == 2 and ".method'" in err and "internal variables" in err


@pytest.mark.parametrize("stages", [1, 2])
def test_a_kinetic_energy_with_linear_terms_keeps_its_jacobi_integral(folder, stages):
    """In a spinning frame T = m/2 |v + W x r|^2 has terms linear in v (M constant, but p = M v + b(q)): the
    energy function h = v.dT/dv - T + V (Jacobi's integral) is conserved by the exact flow, and the run's
    energy_balance_error (which checks h) falls as dt^(2 s) (nothing else is conserved: T + V is not)."""
    system = mechgen.compile(str(folder / "rotating.py"), backend="c")
    steps = [0.04, 0.02, 0.01] if stages == 1 else [0.2, 0.1, 0.05]
    errors = [mechgen.simulate(system, t_end=20.0, method="variational", dt=dt, stages=stages,
                               q0={"x": 1.0, "y": 0.3}, v0={"y": 0.5}).outputs["energy_balance_error"] for dt in steps]
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    print(f"rotating frame, {stages} stage(s): Jacobi integral errors {['%.2e' % e for e in errors]}, "
          f"order {slope:.3f}")
    assert abs(slope - 2 * stages) < 0.3  # the same allowance as the order study
