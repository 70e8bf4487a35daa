"""The analysis kinds, one module each (schema and defaults, kernels, runner, summary, plot), and their registry.

``mechgen.analyses.registry`` lists the kinds; ``mechgen.analyses.public`` holds the Python functions
(``mechgen.modes`` ...), ``mechgen.analyses.result`` their ``Result``. Shared pieces: ``schema``
(option checks), ``operating_point`` (where to linearise), ``whirl`` (damped modes and whirl labels),
``bvp_states`` (outputs and stability of a continuum's steady state), ``parameters``, ``summary``,
``figures``, ``context``. This package defines no attribute of its own: its submodules are its names.
"""
