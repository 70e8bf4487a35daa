"""
A bouncing ball: events, a Zeno stop and the dissipated energy against closed forms
====================================================================================

A ball of mass ``m`` falls under gravity ``g`` from height ``h`` (y in m, t in s); when ``y`` falls through
0 the velocity resets, :math:`\\dot y \\to -e\\,\\dot y` (coefficient of restitution ``e``, written ``cor`` in
the model). Between impacts :math:`\\ddot y = -g`.

The closed forms (any text on hybrid systems, e.g. Goebel, Sanfelice and Teel, *Hybrid Dynamical Systems*,
2012, example 1.1):

* the first impact at :math:`t_1 = \\sqrt{2h/g}` with speed :math:`v_1 = g t_1`; flight ``k`` after it lasts
  :math:`2 e^k v_1 / g`, so the impact times accumulate at the Zeno time

  .. math:: T = t_1 \\frac{1 + e}{1 - e};

* after ``k`` impacts the ball keeps :math:`e^{2k}` of its energy, so the energy dissipated is

  .. math:: D_k = m g h \\left(1 - e^{2k}\\right).

mechgen integrates the flight, locates each impact as an event and, with ``on_zeno="stop"``, ends the run
at the accumulation point instead of refusing it.
"""
import math
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

MODEL = '''\
"""A bouncing ball: flight under gravity; y falling through 0 resets y' -> -cor y'."""
from mechgen import Model, Param

model = Model("gallery_ball", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("g", 9.81, "m/s^2", positive=True),
             Param("cor", 0.8, "", minimum=0.0))
model.coordinates("y")
flight = model.mode("flight")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y


@flight.guard(to="flight", direction="falling", reset=lambda v, p: {"y_dot": -p.cor * v.y})
def floor(q):
    return q.y
'''

folder = Path(tempfile.mkdtemp())
(folder / "ball.py").write_text(MODEL)
ball = mechgen.compile(str(folder / "ball.py"))

m, g, e, h = 1.0, 9.81, 0.8, 1.0
t1 = math.sqrt(2 * h / g)
T = t1 * (1 + e) / (1 - e)

result = mechgen.simulate(ball, t_end=2 * T, q0={"y": h}, method="DOP853", rtol=1e-10, atol=1e-12,
                          on_zeno="stop", zeno_events=20, zeno_span=1e-3, max_events=2000, samples=2001)
print(f"Zeno stop: {result['zeno']}, after {len(result['events'])} impacts")
print(f"accumulation time: mechgen {result['t_final']:.6f} s, closed form {T:.6f} s, "
      f"difference {abs(result['t_final'] - T):.2e} s")
# the stop comes when 21 events fit in zeno_span = 1e-3 s, so it lies within 2e-3 s before T
assert T - 2e-3 < result["t_final"] < T

# %%
# The impact times against the closed form :math:`t_k = t_1 + 2 v_1 \sum_{j=1}^{k-1} e^j / g`:
times = np.array([event["t"] for event in result["events"]])
k = np.arange(len(times))
v1 = g * t1
closed = t1 + 2 * v1 / g * e * (1 - e**k) / (1 - e)
print(f"impact times: max |t_mechgen - t_closed| = {np.max(np.abs(times - closed)):.2e} s")
assert np.max(np.abs(times - closed)) < 1e-8  # events located to the integrator's rtol 1e-10 on times of order 1

# %%
# The dissipated energy at the end of the run against :math:`m g h (1 - e^{2k})` with ``k`` impacts:
k_final = len(times)
expected = m * g * h * (1 - e ** (2 * k_final))
print(f"dissipated: mechgen {result['dissipated']:.9f} J, closed form {expected:.9f} J, "
      f"difference {abs(result['dissipated'] - expected):.2e} J")

# %%
# The same run stopped between the third and fourth impacts, where the closed form keeps
# :math:`e^6` of the energy:
partial = mechgen.simulate(ball, t_end=(closed[2] + closed[3]) / 2, q0={"y": h}, method="DOP853", rtol=1e-10,
                           atol=1e-12)
expected_3 = m * g * h * (1 - e**6)
print(f"dissipated after 3 impacts: mechgen {partial['dissipated']:.9f} J, closed form {expected_3:.9f} J, "
      f"difference {abs(partial['dissipated'] - expected_3):.2e} J")
# each reset's loss is exact up to the velocity at the event, located to rtol 1e-10: 1e-8 J of 9.81 J
assert abs(result["dissipated"] - expected) < 1e-8 and abs(partial["dissipated"] - expected_3) < 1e-8

fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5))
top.plot(result["t"], result["trajectory"]["y"], label="mechgen.simulate")
top.axvline(T, color="k", ls=":", label="closed-form Zeno time T")
top.set_xlabel("t [s]")
top.set_ylabel("y [m]")
top.set_title("Bouncing ball, e = 0.8")
top.legend()
bottom.semilogy(k + 1, np.abs(times - closed) + 1e-18, "o-")
bottom.set_xlabel("impact number")
bottom.set_ylabel("|t_k - closed form| [s]")
fig.tight_layout()
plt.show()
