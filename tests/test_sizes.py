"""Sizes: large continua take the sparse path; what cannot fit is refused up front (issue 12, section 5).

References:
* taut string of tension P, mass per length rhoA, length L, fixed ends: omega_n = (n pi / L) sqrt(P / rhoA)
  (Rao, Vibration of Continuous Systems, 2nd ed., Wiley 2019, eq. 8.26); seen from a frame spinning at
  Omega about the chord, omega_n +- Omega (tests/test_field_strings.py).
* accuracy of the computed eigenvalues: linear elements with consistent mass overestimate lambda = omega^2
  by (k h)^2 / 12 (Hughes, The Finite Element Method, Dover 2000, sec. 9.2); a backward-stable solve adds
  about eps * lambda_max, lambda_max = 12 P / (rhoA h^2), relative to lambda_n: the tolerances below are that
  sum, nothing looser.
* memory of a dense n x n float64 matrix: 8 n^2 bytes (2e6 unknowns: 3.2e13 bytes = 29 TiB).
"""
import json
import os
import subprocess
import sys
import textwrap
import time
import tracemalloc

import numpy as np
import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError
from mechgen.runtime.core import memory

GIB = 2**30
EPS = np.finfo(float).eps

# One analysis of rotating_string with lagrange1 elements in a fresh process; prints its frequencies,
# the wall time of the analysis and the peak resident memory (VmHWM of /proc/self/status:
# ru_maxrss would carry over the forking test process's resident set).
SCRIPT = textwrap.dedent("""
    import json, resource, sys, time
    from threadpoolctl import threadpool_limits
    import mechgen
    def peak_rss():  # this process's own high-water mark (VmHWM, kB); ru_maxrss keeps a forked parent's
        return next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM")) * 1024
    N, kind, omega = int(sys.argv[1]), sys.argv[2], float(sys.argv[3])
    system = mechgen.compile("rotating_string", {"P": 1.0, "rhoA": 1.0, "L": 1.0, "Omega": omega,
                             "discretisation": "lagrange1", "N": N}, kernels=["linear"])
    options = {"count": 6, **({"refine": False} if kind == "stability" else {})}
    with threadpool_limits(1, user_api="blas"):  # BLAS level 2 on a busy machine: threads only contend
        clock = time.perf_counter()
        result = getattr(mechgen, kind)(system, **options)
        seconds = time.perf_counter() - clock
    print(json.dumps({"frequencies": result.outputs["frequencies"], "seconds": seconds, "n": system.n,
                      "maxrss": peak_rss()}))
""")


def string_run(N: int, kind: str = "modes", omega: float = 0.0) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([os.getcwd(), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(N), kind, str(omega)], capture_output=True, text=True,
                         env=env, timeout=900)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def string_tolerance(N: int, omega_n: np.ndarray, L: float = 1.0) -> np.ndarray:
    """Relative bound on omega: half that on lambda, (k h)^2 / 12 + eps lambda_max / lambda_n (P = rhoA = 1)."""
    h = L / N
    lam = omega_n**2
    return 0.5 * (omega_n**2 * h**2 / 12 + EPS * (12 / h**2) / lam)


def exact_string(count_per_field: int = 3) -> np.ndarray:
    """omega_n = n pi (P = rhoA = L = 1), each twice (the two transverse fields v, w)."""
    return np.repeat(np.arange(1, count_per_field + 1) * np.pi, 2)


def dense_bytes_of(n: int) -> int:
    return 8 * n * n


@pytest.mark.slow
def test_string_lowest_modes_at_2e5_elements_sparse():
    """N = 2e5 elements (4e5 unknowns): the six lowest modes against the closed form, in far less memory
    than one dense matrix (1.3e12 bytes)."""
    N = 200_000
    run = string_run(N)
    exact = exact_string()
    error = np.abs(np.array(run["frequencies"]) / exact - 1)
    assert np.all(error <= string_tolerance(N, exact)), (error, string_tolerance(N, exact))
    assert run["n"] == 2 * (N - 1)
    assert run["maxrss"] < 2 * GIB < dense_bytes_of(run["n"]) / 500
    assert run["seconds"] < 60  # about 10 s here on one core; a dense solve would not start


def test_spinning_string_gyroscopic_modes_and_stability_sparse():
    """Omega = 1: the damped-mode and stability paths stay sparse: omega_n - Omega, omega_n + Omega."""
    N = 10_000
    exact = np.sort(np.concatenate([np.arange(1, 4) * np.pi - 1.0, np.arange(1, 4) * np.pi + 1.0]))
    omega_n = np.repeat(np.arange(1, 4) * np.pi, 2)
    # the bound on omega_n carries over to omega_n +- Omega as an absolute error
    bound = string_tolerance(N, omega_n) * omega_n
    for kind in ("modes", "stability"):
        run = string_run(N, kind, 1.0)
        assert np.all(np.abs(np.array(run["frequencies"]) - exact) <= bound), (kind, run["frequencies"])
        assert run["maxrss"] < 1 * GIB < dense_bytes_of(2 * run["n"])


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("MECHGEN_TEST_LARGE"),
                    reason="N = 1e6 (2e6 unknowns) needs about a minute and a few GiB: set MECHGEN_TEST_LARGE=1")
def test_string_lowest_modes_at_1e6_elements():
    """The issue's size: N = 1e6 needs no dense N x N object (one would take 29 TiB)."""
    N = 1_000_000
    run = string_run(N)
    exact = exact_string()
    assert np.all(np.abs(np.array(run["frequencies"]) / exact - 1) <= string_tolerance(N, exact))
    assert run["maxrss"] < 8 * GIB < dense_bytes_of(run["n"]) / 1000


# -------------------------------------------------------------------------------------------- refusals


@pytest.fixture(scope="module")
def spinning():
    """rotating_string as its shipped scene compiles it (sine basis)."""
    return mechgen.compile("rotating_string", {"P": 1.0, "rhoA": 1.0, "L": 1.0, "Omega": 1.0,
                                               "discretisation": "sine", "N": 16}, kernels=["linear"])


def refused_quickly(call):
    """The InputError ``call`` raises, asserting it comes in well under a second (timed untraced, after the
    modules are imported) with almost nothing allocated (a second call under tracemalloc)."""
    with pytest.raises(InputError):
        call()  # imports what the analysis needs
    clock = time.perf_counter()
    with pytest.raises(InputError):
        call()
    seconds = time.perf_counter() - clock
    tracemalloc.start()
    try:
        with pytest.raises(InputError) as info:
            call()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert seconds < 0.5, seconds
    assert peak < 16 << 20, peak
    return info.value


def estimate_gib(message: str) -> float:
    return float(message.split(" needs about ")[1].split(" GiB")[0])


def test_sine_basis_of_a_million_functions_is_refused(spinning, monkeypatch):
    """N = 1e6 with the global sine basis: 2e6 x 2e6 dense matrices (29 TiB each) are refused at params.N."""
    monkeypatch.setenv(memory.ENV, "16GiB")
    exc = refused_quickly(lambda: mechgen.stability(spinning.with_params(N=10**6), count=6))
    assert exc.key == "params.N"
    assert estimate_gib(exc.message) >= 8 * (2 * 10**6) ** 2 / GIB  # at least one dense matrix: 29 TiB
    assert "finite elements" in exc.expected and memory.ENV in exc.expected


def test_quadrature_of_1e5_points_is_refused(spinning, monkeypatch):
    """quadrature = 100000: numpy's Gauss rule builds a 1e5 x 1e5 companion matrix (74.5 GiB)."""
    monkeypatch.setenv(memory.ENV, "16GiB")
    exc = refused_quickly(lambda: mechgen.stability(spinning.with_params(quadrature=100_000), count=6))
    assert exc.key == "params.quadrature"
    assert estimate_gib(exc.message) >= 8e10 / GIB


def test_elements_beyond_memory_are_refused(spinning, monkeypatch):
    """Sparse is not free: 1e8 lagrange1 elements hold 2e8 Gauss points' coefficients; refused at params.N."""
    monkeypatch.setenv(memory.ENV, "16GiB")
    system = spinning.with_params(discretisation="lagrange1", N=10**8)
    exc = refused_quickly(lambda: mechgen.modes(system, count=6))
    assert exc.key == "params.N" and estimate_gib(exc.message) > 16


def test_1e8_samples_are_refused(monkeypatch):
    """samples = 1e8 of a 4-state pendulum: the states alone are 3 GiB (8 x 4 x 1e8 bytes)."""
    monkeypatch.setenv(memory.ENV, "2GiB")
    system = mechgen.compile("spring_pendulum", {"m": 1.0, "k": 40.0, "l0": 1.0, "g": 9.81})
    exc = refused_quickly(lambda: mechgen.simulate(system, t_end=1.0, q0={"r": 1.2, "theta": 0.1},
                                                   samples=10**8))
    assert exc.key == "samples"
    assert estimate_gib(exc.message) >= 8 * 4 * 1e8 / GIB


def test_cli_names_file_key_estimate_and_override(tmp_path, capsys, monkeypatch):
    """Exit 2, one paragraph: the scene file, params.N, the estimate in GiB, the limit and the override."""
    monkeypatch.setenv(memory.ENV, "16GiB")
    scene = tmp_path / "huge_string.toml"
    scene.write_text(textwrap.dedent("""
        title = "huge"
        model = "rotating_string"
        backend = "numpy"
        [params]
        Omega = 1.0
        discretisation = "sine"
        N = 1000000
        [[analysis]]
        name = "whirl"
        kind = "stability"
        count = 6
    """))
    assert main(["run", str(scene)]) == 2
    err = capsys.readouterr().err
    assert str(scene) in err and "'params.N'" in err and "GiB" in err and memory.ENV in err
    assert "16 GiB allowed" in err and "Traceback" not in err


def test_override_off_lets_an_estimate_through_and_bad_values_are_refused(monkeypatch):
    monkeypatch.setenv(memory.ENV, "off")
    memory.require(10**30, "an impossible array", key="params.N")  # no check: nothing raised
    monkeypatch.setenv(memory.ENV, "1MiB")
    with pytest.raises(InputError) as info:
        memory.require_dense(1000, 1, "a test matrix")  # 8e6 bytes > 1 MiB
    assert info.value.key == "params.N" and "0.00745 GiB" in info.value.message
    monkeypatch.setenv(memory.ENV, "lots")
    with pytest.raises(InputError) as info:
        memory.require(1, "anything", key="params.N")
    assert info.value.key == memory.ENV and "64GiB" in info.value.expected


def test_size_units():
    assert memory.parse_size("64GiB") == 64 * GIB
    assert memory.parse_size("500 MB") == 5e8
    assert memory.parse_size("2e9") == 2e9
    assert memory.parse_size("unlimited") is None
    assert memory.dense_bytes(2 * 10**6, 2 * 10**6) == 32 * 10**12  # Python integers: no overflow
    free = memory.available_bytes()
    assert free is None or free > 0
