"""Identifier rules for user-chosen names (models, parameters, coordinates, outputs).

Names reach generated code only as comments and as keys of the kernel spec;
array accesses are generated from positions. Still, every name is checked here
so that a hostile string is an error at declaration time, never text in a file.
"""
from __future__ import annotations

import keyword
import re

from mechgen.errors import ModelError

_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}\Z")
RESERVED = frozenset({"t", "pi", "e", "I", "E", "S", "oo", "nan", "zoo"})


def check_identifier(name: object, *, what: str, file: str | None = None) -> str:
    """Return ``name`` if it is a plain identifier, else raise :class:`ModelError`.

    Accepted: a letter, then up to 63 letters, digits or underscores; not a
    Python keyword; no leading underscore (reserved for generated code).
    """
    if not isinstance(name, str) or not _IDENT.match(name) or keyword.iskeyword(name):
        raise ModelError(f"{what} name {name!r} is not a valid identifier", file=file, key=what,
                         expected="a letter followed by letters, digits or underscores (at most 64)")
    return name
