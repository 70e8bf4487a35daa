"""The friction analyses from Python (mechgen.periodic, mechgen.spectrum, mechgen.stability_boundary): the same
functions a scene runs, checked against closed forms.

* Jenkins element (Griffin 1980; Yang, Chu & Menq 1998): W = 4 mu N (U - mu N/k_u) per cycle;
* rate-and-state spring-slider (Ruina 1983): k_c = sigma (b - a)/D_c, neutral frequency (V/D_c) sqrt((b - a)/a);
* clamped-clamped Euler-Bernoulli beam: f_1 = (4.730040744862704)^2 / (2 pi L^2) sqrt(E I/(rho A)).
"""
import math

import pytest

import mechgen


def test_periodic_from_python_meets_the_jenkins_energy():
    system = mechgen.compile("stick_slip_contact", {"k_u": 1.0, "mu": 0.3, "N": 1.0, "amplitude": 1.0})
    out = mechgen.periodic(system, period=2 * math.pi, force_output="friction_force",
                           displacement_output="tangential_displacement").outputs
    assert out["energy_per_cycle"] == pytest.approx(4 * 0.3 * (1.0 - 0.3), rel=1e-10)


def test_stability_boundary_from_python_meets_ruinas_critical_stiffness():
    system = mechgen.compile("rate_state_slider", {"law": "slip"})
    sigma, a, b, D_c, V2 = 1e7, 0.01, 0.015, 1e-5, 1e-5
    out = mechgen.stability_boundary(system, parameter="k", bracket=[1e7, 1e12]).outputs
    assert out["k_critical"] == pytest.approx(sigma * (b - a) / D_c, rel=1e-10)
    assert out["frequency_critical"] == pytest.approx(V2 / D_c * math.sqrt((b - a) / a), rel=1e-10)


def test_spectrum_from_python_finds_the_first_natural_frequency():
    system = mechgen.compile("friction_beam", {"N": 16, "v_slide": 3.0})  # lock-in at 3 m/s (the scene)
    out = mechgen.spectrum(system, speed="v_slide", spacing="wavelength", start="wavelength/4",
                           impulse="1e-4*sin(2*pi*x/wavelength)", observe="0.1*L", modes=2, damping=1e-4,
                           t_end=1.0, sample_rate=16384).outputs
    L, d, E, rho = 0.28, 0.03, 70e9, 2700.0
    f1 = 4.730040744862704**2 / (2 * math.pi * L**2) * (d / 4) * math.sqrt(E / rho)
    assert out["natural_frequencies"][0] == pytest.approx(f1, rel=1e-5)  # N = 16 Hermite cubics: h^4, ~5e-6
    assert min(abs(p - f1) for p in out["spectrum_peaks"]) <= out["frequency_bin"]
