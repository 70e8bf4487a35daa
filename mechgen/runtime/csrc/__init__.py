"""The runtime's own C sources: the compiled loops and one-call helpers that call generated kernels by address.

They are not templates (code generation never reads them): ``hybrid_loop.c`` (the event-driven DOP853 loop),
``radau_loop.c``, ``field_flow.c`` (a continuum's dx/dt for that loop), ``symplectic_loop.c``,
``variational_loop.c``, ``point_rhs.c`` (dx/dt and its Jacobian in one call) and ``rod_elements.c``. Each
runtime module that builds one names its file with :func:`path` and builds :func:`source`'s text through
mechgen.codegen.build / mechgen.buildlock, which key the build by the text's content. Shared pieces are headers
here (``dense_lu.h``: LU with partial pivoting and its solve), inlined where a source includes them in quotes, so
each library is still built from one text; a header not here is looked up among the generated ones,
``mechgen/generated/liegroup/`` (``liegroup_maps.h``: the so(3) maps written by ``mechgen regen`` from
mechgen/symbolic/liegroup.py). Package data: they ship in the wheel beside this module.
"""
from __future__ import annotations

import re
from pathlib import Path

FOLDER = Path(__file__).resolve().parent
#: where headers not in FOLDER are looked up: the generated Lie-group maps
GENERATED_HEADERS = FOLDER.parent.parent / "generated" / "liegroup"


def path(name: str) -> Path:
    """The file of the runtime C source ``name`` (e.g. ``"hybrid_loop.c"``)."""
    return FOLDER / name

_INCLUDE = re.compile(r'^#include "([A-Za-z0-9_]+\.h)"$', re.M)


def source(name: str | Path) -> str:
    """The text of the runtime C source ``name`` (a file name here, or its :func:`path`), each ``#include "x.h"``
    of a header of this folder (or of :data:`GENERATED_HEADERS`) replaced by the header's text."""
    text = (FOLDER / Path(name).name).read_text(encoding="utf-8")
    return _INCLUDE.sub(lambda m: _header(m.group(1)), text)


def _header(name: str) -> str:
    here = FOLDER / name
    return (here if here.is_file() else GENERATED_HEADERS / name).read_text(encoding="utf-8")
