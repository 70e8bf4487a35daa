"""Escaping of free text (model and parameter docs, choice values) that reaches generated source.

Identifiers reaching generated code are validated (:mod:`mechgen.symbolic.names`); every
other string that a generated file carries as a comment or docstring goes through one
function per target language, so that no text can end the comment, start code or change
what the compiler or interpreter reads:

* :func:`c_comment` -- the body lines of a C block comment: printable ASCII only (other
  characters become ``<U+XXXX>``, control characters a space), no backslash (a line
  splice), no ``??`` (a trigraph; ``??/`` is a backslash), no ``*/`` or ``/*``.
* :func:`py_docstring` -- the text of a ``\"\"\"`` docstring: the same printable-ASCII rule, no
  backslash (an escape), no run of two quotes (``\"\"\"`` would end the string), and no
  quote at the very end (it would join the closing quotes).
"""
from __future__ import annotations

import re


def _printable(text: str) -> str:
    """Printable ASCII and newlines: tabs and other controls become a space, non-ASCII ``<U+XXXX>``."""
    out = []
    for ch in str(text).replace("\r\n", "\n"):
        code = ord(ch)
        if ch == "\n" or 32 <= code < 127:
            out.append(ch)
        elif code < 32 or code == 127 or 0x80 <= code < 0xA0 or ch in "\u2028\u2029\x85":
            out.append(" ")
        else:
            out.append(f"<U+{code:04X}>")
    return "".join(out)


def c_comment(text: object) -> str:
    """``text`` made safe as the inside of a C99 block comment (lines kept, see the module doc)."""
    safe = _printable(str(text)).replace("\\", "/")
    safe = re.sub(r"\?(?=\?)", "? ", safe)
    # after the backslash rule, so that a splice cannot rebuild what these take apart
    safe = re.sub(r"\*(?=/)", "* ", safe)
    safe = re.sub(r"/(?=\*)", "/ ", safe)
    return "\n".join(line.rstrip() for line in safe.split("\n"))


def c_comment_lines(text: object, prefix: str = " * ") -> list[str]:
    """The lines of :func:`c_comment` each with ``prefix`` (an empty line gets ``prefix`` right-stripped)."""
    return [(prefix + line).rstrip() for line in c_comment(text).split("\n")]


def py_docstring(text: object) -> str:
    """``text`` made safe inside a triple-quoted Python docstring (see the module doc)."""
    safe = _printable(str(text)).replace("\\", "/")
    safe = re.sub(r"\"(?=\")", "\" ", safe)
    safe = "\n".join(line.rstrip() for line in safe.split("\n"))
    return safe + " " if safe.endswith('"') else safe
