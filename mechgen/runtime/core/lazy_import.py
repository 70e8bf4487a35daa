"""Modules imported at their first use, so that a scene whose path never needs them starts without them.

``sla = lazy_module("scipy.linalg")`` reads like ``import scipy.linalg as sla``; the import happens at the first
attribute access (``sla.eig``), through ``importlib.import_module`` (the import system's lock makes a first use
from two threads safe), and later accesses go to the imported module directly. scipy.linalg and scipy.sparse
cost 0.2-0.4 s of CPU to import, more than a cached small scene needs to run (issue 30: start).
"""
from __future__ import annotations

import importlib


class LazyModule:
    """The module ``name``, imported at the first attribute read."""

    __slots__ = ("_name", "_module")

    def __init__(self, name: str) -> None:
        self._name = name
        self._module = None

    def __getattr__(self, attr: str):
        module = self._module
        if module is None:
            module = importlib.import_module(self._name)
            self._module = module
        return getattr(module, attr)

    def __repr__(self) -> str:
        state = "imported" if self._module is not None else "not imported yet"
        return f"<lazy module {self._name!r} ({state})>"


def lazy_module(name: str) -> LazyModule:
    """``name`` (a dotted module path), imported when first used."""
    return LazyModule(name)
