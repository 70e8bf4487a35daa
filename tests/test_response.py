"""The ``response`` analysis kind (mechgen/analyses/response.py), added after the registry refactor as one
module plus its registration line. References: closed-form receptances of the Laval rotor (its model doc):
translation m x'' + c x' + k_t x = f gives H_xx = 1 / (k_t - m w^2 + i c w), and y does not move; the
tilts, coupled by the gyroscopic moment Ip Omega, give with a = k_r - Id w^2 + i c_r w
H_11 = a / (a^2 - (w Ip Omega)^2) and |H_21| = w Ip Omega / |a^2 - (w Ip Omega)^2|."""
import numpy as np
import pytest

import mechgen
from mechgen.errors import InputError

P = {"m": 10.0, "Ip": 0.2, "Id": 0.1, "k_t": 4.0e5, "k_r": 2.0e4, "Omega": 300.0, "c": 40.0, "c_r": 2.0}
W = list(np.linspace(10.0, 900.0, 37))


def _tilt(w):
    a = P["k_r"] - P["Id"] * w**2 + 1j * w * P["c_r"]
    det = a**2 - (w * P["Ip"] * P["Omega"]) ** 2
    return a / det, w * P["Ip"] * P["Omega"] / abs(det)


def test_laval_receptances_against_the_closed_forms():
    rotor = mechgen.compile("laval_rotor", P, backend="numpy")
    x = mechgen.analysis("response", rotor, input="x", omega=W, outputs=["x", "y"])
    hxx = 1.0 / (P["k_t"] - P["m"] * np.array(W) ** 2 + 1j * np.array(W) * P["c"])
    assert np.allclose(x["amplitude"]["x"], np.abs(hxx), rtol=1e-10)
    assert np.allclose(x["phase"]["x"], np.angle(hxx), atol=1e-10)
    assert max(x["amplitude"]["y"]) < 1e-12 * max(x["amplitude"]["x"])
    tilt = mechgen.analysis("response", rotor, input="theta_x", omega=W, outputs=["theta_x", "theta_y"])
    h11, h21 = zip(*(_tilt(w) for w in W))
    assert np.allclose(tilt["amplitude"]["theta_x"], np.abs(h11), rtol=1e-9)
    assert np.allclose(tilt["amplitude"]["theta_y"], h21, rtol=1e-9)


def test_a_scene_runs_the_new_kind_and_the_python_call_gives_the_same(tmp_path):
    scene = {"model": "laval_rotor", "params": P,
             "analysis": [{"name": "frf", "kind": "response", "input": "x", "omega": {"start": 10.0, "stop": 900.0,
                                                                                     "num": 37}}]}
    entry = mechgen.run(scene)["analyses"][0]
    direct = mechgen.analysis("response", mechgen.compile("laval_rotor", P), name="frf", input="x", omega=W)
    for name, amplitude in direct["amplitude"].items():
        assert entry["outputs"]["amplitude"][name] == pytest.approx(amplitude, rel=1e-12, abs=1e-300)
    assert direct.to_json()["outputs"]["omega"] == pytest.approx(entry["outputs"]["omega"])
    pytest.importorskip("matplotlib")
    assert [p.name for p in direct.plot(tmp_path)] == ["frf.png"]


def test_bad_options_name_the_key():
    rotor = mechgen.compile("laval_rotor", backend="numpy")
    with pytest.raises(InputError, match="input"):
        mechgen.analysis("response", rotor, input="z", omega=[1.0])
    with pytest.raises(InputError, match="omega"):
        mechgen.analysis("response", rotor, input="x", omega=[-1.0])
    with pytest.raises(InputError, match="omega"):
        mechgen.analysis("response", rotor, input="x")


def test_python_function_response_is_the_closed_form_receptance():
    """mechgen.response (the Python face of the kind): the spring pendulum driven along r at its hanging
    equilibrium r0 = l0 + m g / k: M_rr = m, K_rr = k, so |H_rr| = 1 / (k - m omega^2) below resonance, and no
    coupling into theta at theta = 0 (K and M diagonal there)."""
    import mechgen

    m, k, l0, g = 1.0, 40.0, 1.0, 9.81
    system = mechgen.compile("spring_pendulum")
    r = mechgen.response(system, input="r", omega=[1.0, 2.0, 3.0], at={"r": l0 + m * g / k})
    omega = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(r["amplitude"]["r"], 1.0 / (k - m * omega**2), rtol=1e-12)
    np.testing.assert_allclose(r["amplitude"]["theta"], 0.0, atol=1e-15)
