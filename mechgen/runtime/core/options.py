"""The shared behaviour of the runtime's options objects (ContinuationOptions, CampbellOptions, IVPOptions).

An options object is a frozen dataclass whose field defaults are the defaults of the function it
configures; :meth:`Options.of` merges one with single keyword overrides, so that a function taking
``options`` still accepts every option as a keyword (``continuation(F, u0, lam0, ds=0.1)``).
"""
from __future__ import annotations

import dataclasses


class Options:
    """Mixin of a frozen dataclass of options."""

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The option names."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def of(cls, options=None, **overrides):
        """``options`` (the defaults when None) with ``overrides`` replaced; TypeError on a name that is no option."""
        unknown = sorted(set(overrides) - set(cls.names()))
        if unknown:
            raise TypeError(f"unexpected keyword argument(s) {', '.join(map(repr, unknown))} (the options of "
                            f"{cls.__name__} are {', '.join(cls.names())})")
        return dataclasses.replace(options if options is not None else cls(), **overrides)
