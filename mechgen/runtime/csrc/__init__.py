"""The runtime's own C sources: the compiled loops and one-call helpers that call generated kernels by address.

They are not templates (code generation never reads them): ``hybrid_loop.c`` (the event-driven DOP853 loop),
``radau_loop.c``, ``field_flow.c`` (a continuum's dx/dt for that loop), ``symplectic_loop.c``,
``variational_loop.c``, ``point_rhs.c`` (dx/dt and its Jacobian in one call) and ``rod_elements.c``. Each
runtime module that builds one names its file with :func:`path` and builds the text through
mechgen.codegen.build / mechgen.buildlock, which key the build by the text's content. Package data: they ship in
the wheel beside this module.
"""
from __future__ import annotations

from pathlib import Path

FOLDER = Path(__file__).resolve().parent


def path(name: str) -> Path:
    """The file of the runtime C source ``name`` (e.g. ``"hybrid_loop.c"``)."""
    return FOLDER / name
