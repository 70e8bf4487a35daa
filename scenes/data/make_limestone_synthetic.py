"""Write limestone_synthetic.csv: depths of penetration from the closed form at the paper's resistances.

Frew, Forrestal & Hanchak (2000), "Penetration experiments with limestone targets and ogive-nose steel
projectiles", J. Appl. Mech. 67 (December 2000): three projectile scales (2a = 7.1 mm, 0.020 kg; 12.7 mm, 0.117 kg;
25.4 mm, 0.931 kg; psi = 3) with fitted strength constants R = 913, 787 and 693 MPa. The measured
(Vs, P) tables did not survive the text extraction of the paper, so these rows are SYNTHETIC: the depth
P of eqs. (1a)-(1b) (P = m/(2 pi a^2 rho N) ln(1 + N rho V1^2 / R) + 4a) at striking velocities spread
over the paper's range (0.4-1.9 km/s), rho = 2300 kg/m^3 (Indiana limestone; see the scene's notes).
Fitting R to them recovers the paper's R exactly; they test the procedure, not the experiments.
Run: python scenes/data/make_limestone_synthetic.py
"""
import math
from pathlib import Path

RHO = 2300.0
PSI = 3.0
SCALES = ((7.1e-3, 0.020, 913e6, (500, 650, 800, 950, 1100, 1250, 1400, 1550, 1700, 1850)),
          (12.7e-3, 0.117, 787e6, (400, 550, 700, 850, 1000, 1150, 1300, 1450, 1600, 1750)),
          (25.4e-3, 0.931, 693e6, (450, 600, 750, 900, 1050, 1200, 1350, 1500, 1650, 1900)))


def depth(m: float, a: float, R: float, Vs: float, rho: float = RHO, psi: float = PSI) -> float:
    """P of eqs. (1a)-(1b) (m); the projectile stopping in the crater gives Vs sqrt(m / c), c = pi a R / 4."""
    N = (8 * psi - 1) / (24 * psi**2)
    v1 = (m * Vs**2 - 4 * math.pi * a**3 * R) / (m + 4 * math.pi * a**3 * N * rho)
    if v1 <= 0:
        return Vs * math.sqrt(m / (math.pi * a * R / 4))
    return m / (2 * math.pi * a**2 * rho * N) * math.log(1 + N * rho * v1 / R) + 4 * a


def rows():
    for two_a, m, R, speeds in SCALES:
        for Vs in speeds:
            yield two_a, m, two_a / 2, float(Vs), depth(m, two_a / 2, R, float(Vs))


if __name__ == "__main__":
    lines = ["# SYNTHETIC depths from Frew, Forrestal & Hanchak (2002) eqs. (1a)-(1b) at R = 913, 787, 693 MPa",
             "# (the paper's tables were lost in extraction): made by make_limestone_synthetic.py",
             "two_a,m,a,Vs,P"]
    lines += [",".join(repr(v) for v in row) for row in rows()]
    (Path(__file__).parent / "limestone_synthetic.csv").write_text("\n".join(lines) + "\n")
