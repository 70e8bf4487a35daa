"""Structure-preserving integration for any Lagrangian (issue 25, item 4).

1. The splittings (``simulate``'s ``method = "leapfrog"``, the ``symplectic`` kind) integrate
   q'' = M^-1 (-dV/dq) with a constant diagonal M and nothing else; a model whose derived equations are not
   that (the triple pendulum below: M depends on the angles) is refused at ``method`` (exit 2), while a chain
   (T = u'^2 / 2 per site) still runs.
"""
import subprocess
import sys

import pytest

import mechgen
from mechgen.errors import InputError

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


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("variational_models")
    (path / "triple.py").write_text(TRIPLE)
    (path / "soft_chain.py").write_text(SOFT_CHAIN)
    return path


def run_scene(path, text: str) -> subprocess.CompletedProcess:
    path.write_text(text)
    return subprocess.run([sys.executable, "-m", "mechgen", "run", str(path)], capture_output=True, text=True,
                          timeout=300)


# --------------------------------------------------------------------------- 1. the splittings' refusal

def test_leapfrog_refuses_the_triple_pendulum_at_method(folder, tmp_path):
    """M(q) of the triple pendulum depends on the angles: the leapfrog's division by diag(M(0)) would be wrong,
    so the scene ends with exit 2 at 'method', naming why and the methods to use instead."""
    scene = (f'model = "{folder / "triple.py"}"\n[[analysis]]\nname = "swing"\nkind = "simulate"\nt_end = 1.0\n'
             'method = "leapfrog"\ndt = 0.01\nq0 = { th1 = 1.0 }\n')
    done = run_scene(tmp_path / "leap.toml", scene)
    assert done.returncode == 2, done.stderr
    assert "'method'" in done.stderr and "depends on th1, th2, th3" in done.stderr
    assert "variational" in done.stderr and "Traceback" not in done.stderr
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
