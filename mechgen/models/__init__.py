"""The model library: one module per model family, each defining ``model``.

:func:`get` imports a built-in model by name; :func:`names` lists them.
"""
from __future__ import annotations

import importlib

from mechgen.errors import InputError

BUILTIN = ("balloon_string", "euler_bernoulli_beam", "follower_column", "fpu_chain", "laval_rotor", "moving_string", "spinning_shaft",
           "rotating_string", "spring_pendulum", "timoshenko_beam")


def names() -> list[str]:
    """Names of the built-in models, sorted."""
    return sorted(BUILTIN)


def get(name: str):
    """The :class:`~mechgen.symbolic.model.Model` called ``name``."""
    if name not in BUILTIN:
        raise InputError(f"unknown model {name!r}", key="model", expected=f"one of {', '.join(names())}")
    return importlib.import_module(f"mechgen.models.{name}").model
