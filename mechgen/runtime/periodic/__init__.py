"""Periodic orbits of smooth lumped models: numerics only (no sympy), for ``periodic_orbit`` and, next, for the
continuation of orbits in a parameter.

The interface a continuation builds on, one problem object per method, each holding a compiled system:

* :class:`~mechgen.runtime.periodic.harmonic_balance.HarmonicBalance` (unknowns u: the Fourier coefficients, and
  the frequency omega when autonomous), :class:`~mechgen.runtime.periodic.shooting.Shooting` (u: the start
  state x0, and the period T when autonomous) and :class:`~mechgen.runtime.periodic.collocation.Collocation` (u: the
  states at the mesh's nodes, and T when autonomous) each give

  - ``residual_jacobian(u) -> (R, dR/du)``: the residual, with the phase condition appended when autonomous, and
    its exact Jacobian (square);
  - ``frequency_derivative(u) -> dR/domega`` of a forced orbit at fixed model parameters;
  - ``unknowns(...)`` / ``split(u)``: between u and the orbit's (coefficients, start state or node states;
    frequency or period).

* dR/d(model parameter) is :func:`mechgen.runtime.periodic.parameters.parameter_derivative`: central differences of
  R through ``system.with_params`` (a new system per value; the kernels are those of the compiled model).
* :func:`~mechgen.runtime.periodic.newton.newton` solves R(u) = 0 from a guess; a pseudo-arclength step appends
  one row to the same (R, dR/du).
* :class:`~mechgen.runtime.periodic.conservative.Unfolded` wraps an autonomous problem of a conservative model:
  its free orbits form a family, made isolated by a prescribed level q_p(0) and the unfolding parameter eps of
  Munoz-Almaraz et al. (2003), an unknown that vanishes on the orbit.
* :mod:`~mechgen.runtime.periodic.floquet` turns a monodromy matrix
  (:func:`~mechgen.runtime.periodic.flow.variational_flow`, or a collocation's own
  :meth:`~mechgen.runtime.periodic.collocation.Collocation.monodromy`) into multipliers and stability.
* :func:`~mechgen.runtime.periodic.cycle_guess.closed_cycle` closes the starting guess of a stiff autonomous cycle
  (one period re-integrated from a state near it).

A model with internal variables z has the state x = (q, v, z) at every node and in every start state; collocation
then returns a sparse (CSR) dR/du, which :func:`~mechgen.runtime.periodic.newton.newton` and the continuation solve
by SuperLU.
"""
