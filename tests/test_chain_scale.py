"""fpu_chain's ``ends`` choice, and a chain of 10^6 particles in memory O(N).

References: fixed ends omega_k = 2 sin(k pi / (2 (N+1))), k = 1..N; periodic ends omega_k = 2 |sin(k pi / N)|,
k = 0..N-1 (the circulant stiffness), both from the one bond energy of the model.
"""
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import mechgen


@pytest.mark.parametrize("ends", ["fixed", "periodic"])
def test_ends_choice_frequencies(ends):
    N = 12
    system = mechgen.compile("fpu_chain", {"N": N, "alpha": 0.0, "ends": ends}, kernels=["linear", "force"])
    assert system.metadata.ends == ends
    w2 = np.sort(np.linalg.eigvalsh(system.linear()["K"].toarray()))
    if ends == "fixed":
        expected = 4 * np.sin(np.arange(1, N + 1) * np.pi / (2 * (N + 1))) ** 2
    else:
        expected = np.sort(4 * np.sin(np.arange(N) * np.pi / N) ** 2)
    assert np.allclose(w2, expected, atol=1e-13)


def test_periodic_force_is_translation_invariant():
    system = mechgen.compile("fpu_chain", {"N": 10, "alpha": 0.25, "beta": 0.5, "ends": "periodic"},
                             kernels=["force"])
    q = np.random.default_rng(0).standard_normal(10)
    assert np.allclose(system.force(q + 3.0), system.force(q), atol=1e-12)
    assert abs(system.force(q).sum()) < 1e-12  # the bond forces cancel in pairs: total momentum conserved


# N = 10^6 in a fresh process: its peak RSS is the chain's alone (a forked child starts with the test
# process's resident set, so a large in-process run would also inflate later tests' measurements).
MILLION = textwrap.dedent("""
    import json, sys
    import numpy as np
    import scipy.sparse.linalg as spla
    import mechgen
    def peak_rss():  # this process's own high-water mark (VmHWM, kB); ru_maxrss keeps a forked parent's
        return next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM")) * 1024
    from mechgen.runtime.core.symplectic_c import evolve_system
    from mechgen.runtime.linear.chain_modes import mode_shape
    N = int(sys.argv[1])
    system = mechgen.compile("fpu_chain", {"N": N, "alpha": 0.25}, kernels=["linear", "force", "outputs"])
    K = system.linear()["K"]
    w2 = np.sort(spla.eigsh(K.tocsc(), k=4, sigma=0.0, which="LM", return_eigenvectors=False))
    shape = mode_shape(N, 1)
    q, v, e, used = evolve_system(system, shape / shape.max(), np.zeros(N), 0.1, 20, "aba864", stride=10)
    print(json.dumps({"w": np.sqrt(w2).tolist(), "used": used, "drift": abs(e[-1] - e[0]) / e[0],
                      "maxrss": peak_rss()}))
""")


@pytest.mark.slow
def test_million_particles_in_bounded_memory():
    """N = 10^6: the lowest modes by shift-invert Lanczos on the sparse K (scipy eigsh), and steps in C."""
    N = 1_000_000
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([os.getcwd(), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", MILLION, str(N)], capture_output=True, text=True, env=env,
                         timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    run = json.loads(out.stdout.strip().splitlines()[-1])
    k = np.arange(1, 5)
    assert np.allclose(run["w"], 2 * np.sin(k * np.pi / (2 * (N + 1))), rtol=1e-6)
    assert run["used"] == "c" and run["drift"] < 1e-10
    peak = run["maxrss"]
    print(f"peak RSS {peak / 2**20:.0f} MiB at N = {N:,} (a dense N x N would be {8 * N**2 / 2**40:.0f} TiB)")
    assert peak < 3 * 2**30  # O(N): a few hundred bytes per particle, never an N x N object (8 TB)


def test_simulate_initial_mode_of_a_long_chain_needs_no_dense_eigenproblem():
    """simulate's ``initial_mode`` on 20 000 sites: the sparse shift-invert shape equals sin(n k pi / (N+1))."""
    from mechgen.analyses.simulate import initial_state
    from mechgen.runtime.linear.chain_modes import mode_shape

    N = 20_000
    system = mechgen.compile("fpu_chain", {"N": N}, kernels=["force", "outputs", "linear"])
    q, _ = initial_state(system, {"initial_mode": 2, "amplitude": 1.0})
    ref = mode_shape(N, 2) / np.abs(mode_shape(N, 2)).max()
    assert min(np.abs(q - ref).max(), np.abs(q + ref).max()) < 1e-8
