"""Time integration with events: one set of rules, two loops, one options object.

The rules (guards found on every step by their Hermite interpolants, grazing, simultaneous events, events at
t = 0, Zeno approaches) are stated once, in the module doc of :mod:`mechgen.runtime.integration.events`. The
Python loop there (scipy's steppers) and the compiled DOP853 loop of :mod:`mechgen.runtime.integration.events_c`
(``runtime/csrc/hybrid_loop.c``) apply them alike and read the same
:class:`~mechgen.runtime.integration.run_options.RunOptions`; a smooth model is the case without guards
(:mod:`~mechgen.runtime.integration.smooth_c`), a continuum a flow provider of the same C loop
(:mod:`mechgen.runtime.fields.flow_c`). :mod:`~mechgen.runtime.integration.augmented` carries the energy
balance's integrals with the state in either loop. A smooth lumped model's implicit method has its compiled loop
too: :mod:`~mechgen.runtime.integration.radau_c` (scipy's Radau step for step, ``runtime/csrc/radau_loop.c``).
"""
