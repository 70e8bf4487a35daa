"""Numerics on generated kernels: never imports sympy or mechgen.symbolic.

Grouped by what the modules do (each subpackage's ``__init__`` is empty, so importing one
module loads only what it needs):

* :mod:`~mechgen.runtime.core` - kernels (loading generated code), the compiled lumped/lattice
  ``System`` and its typed ``SystemMeta``, options objects, sparsity patterns, time integration and parallel sweeps;
* :mod:`~mechgen.runtime.linear` - linear analyses about an operating point and rotor
  post-processing: undamped modes, stability, damped modes, Campbell diagrams;
* :mod:`~mechgen.runtime.steady` - steady states and boundary-value problems: Newton,
  shooting and collocation, pseudo-arclength continuation, branch scans and their stability,
  constrained linearisation and starting guesses;
* :mod:`~mechgen.runtime.fields` - continuum discretisation and assembly: meshes, bases,
  reference elements, Galerkin discretisations, assembly, constraints and the ``FieldSystem``.

Imports point one way: ``core`` needs nothing else here, ``linear`` and ``fields`` build on
``core``, ``steady`` on all three; nothing imports back (tests/test_imports.py).
"""
