"""Identifier rules for user-chosen names (models, parameters, coordinates, outputs).

Names reach generated code only as comments and as keys of the kernel spec;
array accesses are generated from positions. Still, every name is checked here
so that a hostile string is an error at declaration time, never text in a file.
"""
from __future__ import annotations

import keyword
import re
import sys
from pathlib import Path

from mechgen.errors import ModelError

_SYMBOLIC = Path(__file__).resolve().parent
_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}\Z")
RESERVED = frozenset({"t", "pi", "e", "I", "E", "S", "oo", "nan", "zoo"})


def declaring_file() -> str | None:
    """The file of the innermost caller outside mechgen.symbolic: where a declaration was written.

    None when that caller is not a file (an interactive session).
    """
    frame = sys._getframe(1)
    while frame is not None:
        name = frame.f_code.co_filename
        if name != "<string>" and Path(name).resolve().parent != _SYMBOLIC:  # "<string>": a dataclass __init__
            return name if Path(name).is_file() else None
        frame = frame.f_back
    return None


def check_identifier(name: object, *, what: str, file: str | None = None) -> str:
    """Return ``name`` if it is a plain identifier, else raise :class:`ModelError`.

    Accepted: a letter, then up to 63 letters, digits or underscores; not a
    Python keyword; no leading underscore (reserved for generated code). The
    error names ``file``, else the file the declaration was written in.
    """
    if isinstance(name, str) and keyword.iskeyword(name):
        raise ModelError(f"{what} name {name!r} is a Python keyword, not a valid identifier "
                         f"(.{name} cannot be written in Python)", file=file or declaring_file(), key=what,
                         expected=f"a name that is not a Python keyword, e.g. {name}_")
    if not isinstance(name, str) or not _IDENT.match(name):
        raise ModelError(f"{what} name {name!r} is not a valid identifier", file=file or declaring_file(), key=what,
                         expected="a letter followed by letters, digits or underscores (at most 64)")
    return name
