"""Symplectic splitting methods for a separable Hamiltonian H = T(p) + V(q), T = p^T M^-1 p / 2.

A method is a composition of the exact flows of the two parts over one step h,

    phi_h = e^{b_0 h B} e^{a_1 h A} e^{b_1 h B} e^{a_2 h A} ... e^{a_s h A} e^{b_s h B},

A: the drift q += a h v (the flow of T), B: the kick v += b h M^-1 f(q) (the flow of V, f = -dV/dq).
Consistency needs sum a = sum b = 1; every method here is symmetric (time-reversible), hence of
even order. The coefficients (:data:`METHODS`):

* ``leapfrog`` - velocity Verlet (Stormer-Verlet), b = (1/2, 1/2), a = (1): order 2.
* ``yoshida4`` - the triple jump of leapfrogs with weights (w1, w0, w1), w1 = 1/(2 - 2^(1/3)),
  w0 = 1 - 2 w1 (Yoshida 1990, Phys. Lett. A 150, 262, eq. 5.19; Forest & Ruth 1990): order 4.
* ``yoshida6`` - the symmetric composition of 7 leapfrogs (w3, w2, w1, w0, w1, w2, w3), Yoshida's
  solution A (ibid., Table 1): w1 = -1.17767998417887, w2 = 0.235573213359357,
  w3 = 0.784513610477560, w0 = 1 - 2 (w1 + w2 + w3): order 6.
* ``aba864`` - ABA864 of Blanes, Casas, Farres, Laskar, Makazaga & Murua (2013), "New families of
  symplectic splitting methods for numerical integration in dynamical astronomy", Appl. Numer. Math.
  68, 58-72, Table 2: the symmetric ABA method a1 b1 a2 b2 a3 b3 a4 b4 a4 b3 a3 b2 a2 b1 a1, order 4
  in general and order (8, 6, 4) for a perturbed integrable H = H0 + eps H1 (errors
  O(eps h^8 + eps^2 h^6 + eps^3 h^4)), designed for near-integrable systems such as FPU chains.

Runtime module: numbers only (no sympy). :func:`evolve` is the numpy stepper (one force call per
kick; the first kick of a step reuses the last kick's force when no drift lies between them).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class Splitting:
    """A splitting method: kicks ``b`` (s + 1 entries, b[0] before the first drift) and drifts ``a`` (s)."""

    name: str
    order: int
    a: tuple[float, ...]
    b: tuple[float, ...]
    reference: str = ""

    @property
    def forces_per_step(self) -> int:
        """Force evaluations per step (the end kicks of consecutive steps share one)."""
        nonzero = [x != 0.0 for x in self.b]
        return sum(nonzero) - (1 if nonzero[0] and nonzero[-1] else 0)


def compose_leapfrogs(name: str, order: int, weights, reference: str = "") -> Splitting:
    """The composition of velocity-Verlet steps of lengths w_i h: kick w/2, drift w, kick w/2, kicks merged."""
    weights = [float(w) for w in weights]
    b = [weights[0] / 2]
    for w, w_next in zip(weights[:-1], weights[1:]):
        b.append((w + w_next) / 2)
    b.append(weights[-1] / 2)
    return Splitting(name, order, tuple(weights), tuple(b), reference)


def _yoshida4() -> Splitting:
    w1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
    return compose_leapfrogs("yoshida4", 4, (w1, 1.0 - 2.0 * w1, w1), "Yoshida 1990, Phys. Lett. A 150, 262")


def _yoshida6() -> Splitting:
    w1, w2, w3 = -1.17767998417887, 0.235573213359357, 0.784513610477560
    w0 = 1.0 - 2.0 * (w1 + w2 + w3)
    return compose_leapfrogs("yoshida6", 6, (w3, w2, w1, w0, w1, w2, w3),
                             "Yoshida 1990, Phys. Lett. A 150, 262, solution A")


def _aba864() -> Splitting:
    a = (0.0711334264982231177779387300061549964174, 0.241153427956640098736487795326289649618,
         0.521411761772814789212136078067994229991, -0.333698616227678005726562603400438876027)
    b = (0.183083687472197221961703757166430291072, 0.310782859898574869507522291054262796375,
         -0.0265646185119588006972121379164987592663, 0.0653961422823734184293734557682160040917)
    drifts = a + a[::-1]
    kicks = (0.0,) + b + b[:3][::-1] + (0.0,)
    return Splitting("aba864", 4, drifts, kicks,
                     "Blanes, Casas, Farres, Laskar, Makazaga & Murua 2013, Appl. Numer. Math. 68, 58")


METHODS: dict[str, Splitting] = {
    "leapfrog": compose_leapfrogs("leapfrog", 2, (1.0,), "velocity Verlet"),
    "yoshida4": _yoshida4(),
    "yoshida6": _yoshida6(),
    "aba864": _aba864(),
}


def method(name: str) -> Splitting:
    """The splitting method ``name`` (KeyError naming the known ones)."""
    if name not in METHODS:
        raise KeyError(f"unknown integrator {name!r}; expected one of {', '.join(METHODS)}")
    return METHODS[name]


def evolve(acceleration: Callable[[np.ndarray], np.ndarray], q, v, dt: float, n_steps: int,
           splitting: Splitting | str = "leapfrog", *, stride: int = 0,
           observe: Callable[[np.ndarray, np.ndarray], object] | None = None):
    """Advance (q, v) by ``n_steps`` steps of ``dt`` with ``splitting``; a(q) = M^-1 f(q).

    Returns (q, v, records): ``observe(q, v)`` at step 0 and every ``stride`` steps (stride > 0).
    """
    split = method(splitting) if isinstance(splitting, str) else splitting
    q, v = np.array(q, float), np.array(v, float)
    a_h = [x * dt for x in split.a]
    b_h = [x * dt for x in split.b]
    records = [observe(q, v)] if observe is not None and stride > 0 else []
    acc = None  # the acceleration at the current q, when known
    for step in range(1, n_steps + 1):
        for i, drift in enumerate(a_h):
            if b_h[i] != 0.0:
                if acc is None:
                    acc = acceleration(q)
                v += b_h[i] * acc
            q += drift * v
            acc = None
        if b_h[-1] != 0.0:
            acc = acceleration(q)
            v += b_h[-1] * acc
        if records is not None and stride > 0 and observe is not None and step % stride == 0:
            records.append(observe(q, v))
    return q, v, records


__all__ = ["METHODS", "Splitting", "compose_leapfrogs", "evolve", "method"]


def splitting_refusal(system) -> str | None:
    """Why ``system`` is not fit for a splitting (leapfrog included), from its force kernel's meta, or None.

    The force kernel records (mechgen.codegen.lower_lumped.separable_meta, decided symbolically on the
    specialised equations) whether Lagrange's equations are q'' = M^-1 (-dV/dq) with a constant diagonal M and
    no other term; a kernel that does not record it (built by an older mechgen) is not trusted either.
    """
    kernel = system.kernels.get("force")
    if kernel is None:
        return "it has no potential force kernel (no coordinates?)"
    meta = kernel.spec.get("meta", {})
    if "separable" not in meta:
        return "its force kernel does not record whether its kinetic energy is a constant diagonal quadratic form"
    if meta["separable"]:
        return None
    return meta.get("separable_why") or "its equations are not q'' = M^-1 (-dV/dq) with a constant diagonal M"


def require_separable(system, key: str, what: str, instead: str) -> None:
    """InputError at ``key`` (exit 2) when ``system`` is not fit for the splitting ``what`` (splitting_refusal),
    naming why and ``instead``, what to use; nothing otherwise."""
    from mechgen.errors import InputError

    why = splitting_refusal(system)
    if why:
        raise InputError(f"{what} integrates q'' = M^-1 (-dV/dq) with a constant diagonal mass matrix M and no other "
                         f"term, and model {system.metadata.model} does not fit: {why}", key=key, expected=instead)
