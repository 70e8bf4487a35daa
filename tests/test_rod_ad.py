"""CasADi AD Jacobians of the rods' local pieces (mechgen.runtime.rods.ad / local) against independent
references: the numpy Lie-group maps (closed forms with their own series, tests/test_liegroup_numeric.py)
and central differences of the numpy residuals (truncation O(eps^2) ~ 1e-12, round-off ~1e-10 relative)."""
from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from mechgen.runtime.rods import ad, liegroup as lg
from mechgen.runtime.rods import statics as st

ANGLES = [0.0, 1e-12, 1e-6, 1e-3, 0.3, 0.99, 1.01, 2.0, 3.0]


def _sx(fn, size):
    x = ca.SX.sym("x", size)
    return ca.Function("f", [x], [fn(x)])


@pytest.mark.parametrize("t", ANGLES)
def test_sx_maps_equal_the_numpy_maps_at_every_angle(t):
    rng = np.random.default_rng(int(1e6 * t) % 1000)
    axis = rng.normal(size=3)
    w = t * axis / np.linalg.norm(axis)
    v = rng.normal(size=3)
    xi = np.concatenate([v, w])
    for sx, ref in ((ad.exp_so3, lg.exp_so3), (ad.jac_left_so3, lg.jac_left_so3),
                    (ad.jac_left_so3_inv, lg.jac_left_so3_inv)):
        assert np.abs(np.array(_sx(sx, 3)(w)) - ref(w)).max() < 5e-16 * max(1.0, t**2)
    R = lg.exp_so3(w)
    R_sym = ca.SX.sym("R", 3, 3)
    log = ca.Function("log", [R_sym], [ad.log_so3(R_sym)])
    assert np.abs(np.array(log(R)).ravel() - w).max() < 2e-15
    a = ca.SX.sym("a", 6)
    Q = ca.Function("q", [a], [ad.q_block(a[:3], a[3:])])
    assert np.abs(np.array(Q(xi)) - lg.jac_left_se3(xi)[:3, 3:]).max() < 1e-14 * max(1.0, np.abs(v).max())
    eta = rng.normal(size=6)
    b = ca.SX.sym("b", 6)
    D = ca.Function("d", [a, b], [ad.dexp_inv_right(a, b)])
    ref = np.linalg.solve(lg.jac_right_se3(xi), eta)
    assert np.abs(np.array(D(xi, eta)).ravel() - ref).max() < 1e-13 * np.abs(ref).max()


def test_derivatives_at_zero_angle_are_the_series_ones():
    """d exp(hat w)/dw at w = 0 is the generator hat(e_k); d log(R)/dR at I is finite (no 0/0 leaks)."""
    w = ca.SX.sym("w", 3)
    J = ca.Function("J", [w], [ca.jacobian(ad.flat(ad.exp_so3(w)), w)])(np.zeros(3))
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1.0
        assert np.abs(np.array(J)[:, k].reshape(3, 3) - lg.hat3(e)).max() == 0.0
    R = ca.SX.sym("R", 3, 3)
    dlog = ca.Function("dl", [R], [ca.jacobian(ad.log_so3(R), ca.vec(R))])(np.eye(3))
    assert np.all(np.isfinite(np.array(dlog)))


def _load(r):
    """A position-dependent spatial load (force, torque per length) with all components coupled."""
    r = np.asarray(r, dtype=float).reshape(-1, 3)
    g = np.zeros((len(r), 6))
    g[:, 1] = -0.5 + 0.3 * r[:, 0]
    g[:, 2] = 0.2 * r[:, 1] ** 2
    g[:, 3] = 0.1 * r[:, 2]
    g[:, 5] = 0.05 * r[:, 0] * r[:, 1]
    return g


def _uniform(r):
    g = np.zeros((len(np.asarray(r).reshape(-1, 3)), 6))
    g[:, 1], g[:, 5] = -0.7, 0.2
    return g


def _rod(base, tip, load=None, uniform=False):
    K = np.diag([100.0, 50.0, 50.0, 2.0, 1.0, 1.5])
    K[1, 5] = K[5, 1] = 0.3                                     # a shear-bending coupling
    return st.Rod(1.3, K, f0=np.array([1.0, 0, 0, 0, 0.3, 0.1]), load=load, tip_force=np.array([0.1, -0.3, 0.2]),
                  tip_torque=np.array([0.1, 0.2, -0.1]), base=base, tip=tip, load_uniform=uniform)


ENDS = [("clamped", "free"), ("pinned", "pinned"), ("clamped", "clamped"), ("pinned", "clamped"),
        ("free", "clamped")]


@pytest.mark.parametrize("base,tip", ENDS)
def test_collocation_jacobian_by_ad_equals_central_differences(base, tip):
    rod = _rod(base, tip, _load)
    n, lam = 6, 0.7
    rng = np.random.default_rng(3)
    ref = st.straight(rod, n)
    H, sigma = st.perturbed(rod, ref.H, ref.sigma, 0.3 * rng.normal(size=(n + 1, 12)))
    J = st.collocation_jacobian(rod, H, sigma, lam).toarray()
    eps = 1e-6
    Jc = np.zeros_like(J)
    for j in range(J.shape[1]):
        d = np.zeros(J.shape[1])
        d[j] = eps
        plus = st.perturbed(rod, H, sigma, d.reshape(n + 1, 12))
        minus = st.perturbed(rod, H, sigma, -d.reshape(n + 1, 12))
        Jc[:, j] = (st.collocation_residual(rod, *plus, lam) - st.collocation_residual(rod, *minus, lam)) / (2 * eps)
    assert np.abs(J - Jc).max() < 1e-8 * np.abs(Jc).max()
    # the forward-difference Jacobian (kept as method="fd") agrees to its O(eps) error
    fd = st.collocation_jacobian(rod, H, sigma, lam, method="fd").toarray()
    assert np.abs(fd - J).max() < 1e-5 * np.abs(J).max()


@pytest.mark.parametrize("base,tip", [("clamped", "free"), ("pinned", "pinned"), ("free", "clamped")])
@pytest.mark.parametrize("load", ["none", "position", "uniform"])
def test_shooting_jacobian_by_ad_equals_central_differences(base, tip, load):
    """Both AD paths: numpy nodes + mapped step transfers (a position-dependent load) and the CasADi fold
    (no load, a uniform load)."""
    rod = _rod(base, tip, {"none": None, "position": _load, "uniform": _uniform}[load], load == "uniform")
    z = 0.3 * np.random.default_rng(5).normal(size=12)
    steps, lam = 10, 0.7
    r, J = st.shooting_jacobian(rod, z, steps, lam)
    assert np.abs(r - st.shooting_residual(rod, z, steps, lam)).max() < 1e-14
    eps = 1e-6
    Jc = np.column_stack([(st.shooting_residual(rod, z + d, steps, lam) - st.shooting_residual(rod, z - d, steps, lam))
                          / (2 * eps) for d in eps * np.eye(12)])
    assert np.abs(J - Jc).max() < 1e-8 * np.abs(Jc).max()


def test_load_gradient_from_the_generated_kernel_matches_differences():
    """rod_of's load Jacobian is the kernel's generated g_r: the centrifugal load rhoA omega^2 (x, y, 0) plus
    gravity of the rotating beam (seed 001, Exercise 2) against central differences of the load; a uniform
    load is flagged so (and its Jacobian is zero)."""
    import mechgen
    from mechgen.analyses.rod_statics import rod_of

    options = {"tip_force": [0.0, 0.0, 0.0], "tip_torque": [0.0, 0.0, 0.0], "base": "clamped", "tip": "free"}
    spinning = rod_of(mechgen.compile("cosserat_rod", {"rhoA": 2.0, "omega": 3.0, "g_y": -9.81},
                                      backend="numpy"), options)
    assert not spinning.load_uniform and spinning.load_jacobian is not None
    r = np.random.default_rng(2).normal(size=(4, 3))
    g, G = st.load_and_gradient(spinning, r)
    d = 1e-5
    Gc = np.stack([(spinning.load(r + d * e) - spinning.load(r - d * e)) / (2 * d) for e in np.eye(3)], axis=-1)
    assert np.abs(G - Gc).max() < 1e-9 and abs(G[0, 0, 0] - 2.0 * 9.0) < 1e-12
    hanging = rod_of(mechgen.compile("cosserat_rod", {"rhoA": 2.0, "g_y": -9.81}, backend="numpy"), options)
    assert hanging.load_uniform and np.all(st.load_and_gradient(hanging, r)[1] == 0.0)


@pytest.mark.parametrize("method", ["collocation", "shooting"])
def test_ad_and_fd_newton_reach_the_same_state(method):
    """The tip-load elastica PL^2/EI = 10 (Mattiasson 1981: tip (0.4450, -0.8116) L at EA/EI = 1e4): the
    AD and finite-difference Jacobians give the same converged state (to the Newton tolerance), AD in no
    more iterations."""
    rod = st.Rod(1.0, np.diag([1e4, 1e4, 1e4, 1.0, 1.0, 1.0]), tip_force=np.array([0.0, -10.0, 0.0]))
    paths = {m: st.solve_statics(rod, method=method, elements=20, jacobian=m) for m in ("ad", "fd")}
    a, f = paths["ad"].final, paths["fd"].final
    assert np.abs(a.H[:, :3, 3] - f.H[:, :3, 3]).max() < 1e-9
    assert sum(s.iterations for s in paths["ad"].states) <= sum(s.iterations for s in paths["fd"].states)
    assert abs(a.H[-1, 0, 3] - 0.4450) < 2e-3 and abs(a.H[-1, 1, 3] + 0.8116) < 2e-3


def test_unknown_jacobian_method_is_refused():
    rod = st.Rod(1.0, np.eye(6))
    with pytest.raises(ValueError, match="ad or fd"):
        st.solve_statics(rod, jacobian="exact")


def _band_to_dense(ab: np.ndarray, band: int) -> np.ndarray:
    size = ab.shape[1]
    J = np.zeros((size, size))
    for j in range(size):
        for i in range(max(0, j - band), min(size, j + band + 1)):
            J[i, j] = ab[2 * band + i - j, j]
    return J


@pytest.mark.parametrize("base,tip", [("clamped", "free"), ("pinned", "pinned"), ("free", "free"),
                                      ("clamped", "clamped")])
@pytest.mark.parametrize("load", [None, _load])
def test_dynamics_step_jacobian_by_ad_equals_central_differences(base, tip, load):
    """The midpoint/theta step's band Jacobian (damping, gyroscopic term, a position-dependent load, tip
    wrench, fixed rows) by AD against central differences of the numpy residual, at a generic state."""
    from mechgen.runtime.rods import dynamics as dy

    rod = _rod("clamped", "free", load)
    body = dy.RodBody(rod, np.diag([2.0, 2.0, 2.0, 0.01, 0.02, 0.015]), damping=0.3, alpha=0.6)
    n_el = 5
    disc = dy.Discrete(body, n_el, base, tip)
    rng = np.random.default_rng(1)
    S = dy.reference_state(body, n_el)
    S.x += 0.05 * rng.normal(size=S.x.shape)
    S.R = S.R @ dy.exp_so3(0.3 * rng.normal(size=(n_el + 1, 3)))
    S.v, S.w = rng.normal(size=S.x.shape), rng.normal(size=S.x.shape)
    z, dt = 0.05 * rng.normal(size=(n_el + 1, 6)), 0.01
    J = _band_to_dense(disc.jacobian_band(S, z, dt), dy.BAND)
    eps, size = 1e-6, 6 * (n_el + 1)
    Jc = np.zeros((size, size))
    for j in range(size):
        d = np.zeros(size)
        d[j] = eps
        plus = disc.residual(S, z + d.reshape(z.shape), dt)[0]
        minus = disc.residual(S, z - d.reshape(z.shape), dt)[0]
        Jc[:, j] = (plus - minus).ravel() / (2 * eps)
    assert np.abs(J - Jc).max() < 1e-9 * np.abs(Jc).max()
    fd = _band_to_dense(disc.jacobian_band(S, z, dt, method="fd"), dy.BAND)
    assert np.abs(fd - J).max() < 1e-6 * np.abs(J).max()


def test_dynamics_with_ad_and_fd_jacobians_reach_the_same_trajectory():
    """A cantilever released under gravity: both Jacobians drive Newton to the same states (to tol)."""
    from mechgen.runtime.rods import dynamics as dy

    rod = st.Rod(1.0, np.diag([1e4, 1e4, 1e4, 1.0, 1.0, 1.0]), load=_uniform, load_uniform=True)
    disc = dy.Discrete(dy.RodBody(rod, np.diag([1.0, 1.0, 1.0, 2e-3, 1e-3, 1e-3])), 10)
    runs = {m: dy.simulate(disc, dy.reference_state(disc.body, 10), dt=0.01, t_end=0.3, jacobian=m)
            for m in ("ad", "fd")}
    assert np.abs(np.array(runs["ad"].tip) - np.array(runs["fd"].tip)).max() < 1e-9
    assert runs["ad"].newton_iterations <= runs["fd"].newton_iterations
    with pytest.raises(ValueError, match="ad or fd"):
        dy.simulate(disc, dy.reference_state(disc.body, 10), dt=0.01, t_end=0.01, jacobian="exact")


def test_without_a_compiler_the_pieces_run_in_casadis_virtual_machine(monkeypatch):
    """A missing compiler is not an error: the same Jacobian from the SX function."""
    from mechgen.runtime.rods import local

    rod = _rod("clamped", "free", _load)
    ref = st.straight(rod, 4)
    H, sigma = st.perturbed(rod, ref.H, ref.sigma, 0.2 * np.random.default_rng(0).normal(size=(5, 12)))
    compiled = st.collocation_jacobian(rod, H, sigma, 0.5).toarray()
    if local.native("collocation_element").class_name() != "External":
        pytest.skip("no C compiler here: the compiled path is not there to compare with")
    local.native.cache_clear()
    monkeypatch.setenv("CC", "/nonexistent/cc")
    try:
        assert local.native("collocation_element").class_name() == "SXFunction"
        vm = st.collocation_jacobian(rod, H, sigma, 0.5).toarray()
    finally:
        local.native.cache_clear()
    assert np.abs(vm - compiled).max() <= 1e-14 * np.abs(compiled).max()


def test_the_jacobian_key_from_scenes_and_python(tmp_path, capsys):
    """``jacobian = "fd"`` through the Python API gives the AD run's numbers (to the Newton tolerance); a
    bad value exits 2 naming the key and the scene file."""
    import mechgen
    from mechgen.cli import main

    system = mechgen.compile("cosserat_rod", {"rhoA": 1.0, "rhoI": 1e-3, "rhoJ": 2e-3, "g_y": -9.81})
    runs = [mechgen.rod_dynamics(system, elements=8, dt=0.01, t_end=0.1, jacobian=m).outputs for m in ("ad", "fd")]
    assert np.abs(np.array(runs[0]["tip_trajectory"]) - np.array(runs[1]["tip_trajectory"])).max() < 1e-9
    statics = [mechgen.rod_statics(system, elements=8, jacobian=m).outputs for m in ("ad", "fd")]
    assert np.abs(np.array(statics[0]["shape"]) - np.array(statics[1]["shape"])).max() < 1e-10
    scenes = __import__("pathlib").Path(__file__).resolve().parents[1] / "scenes"
    scene = tmp_path / "bad.toml"
    scene.write_text((scenes / "rod_dynamics.toml").read_text() + '\njacobian = "exact"\n')
    assert main(["run", str(scene)]) == 2
    err = capsys.readouterr().err
    assert "jacobian" in err and "bad.toml" in err and "Traceback" not in err


def test_batched_buffers_give_the_ordinary_calls_numbers():
    """local.Batched (CasADi's FunctionBuffer on bound numpy arrays, the dynamics Jacobian's path) against the
    ordinary mapped call of the same function, the sparse node piece's structural zeros included, and its
    fallback for a CasADi without FunctionBuffer: equal exactly (the same compiled code on the same numbers)."""
    from mechgen.runtime.rods import local

    rng = np.random.default_rng(4)
    for name in ("dynamics_element", "dynamics_node"):
        g = local.native(name)
        batched = local.Batched(g, 7)
        data, par = rng.normal(size=(7, g.nnz_in(0))), rng.normal(size=g.nnz_in(1))
        ordinary = np.asarray(local.mapped(g, 7)(data.T, par)).T
        assert np.array_equal(batched(data, par), ordinary)
        batched.buffer = None
        assert np.array_equal(batched(data, par), ordinary)
