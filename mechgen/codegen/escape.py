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
* :func:`py_literal` -- a JSON-like value as a Python literal (the ``SPEC`` of a generated
  module): strings by ``repr``, finite numbers only, read back with ``ast.literal_eval``.
* :func:`code_identifier` -- the guard on every variable name the printers and emitters write
  (after lowering only ``g0, t0 ...``): no user text, keyword or name the module binds itself.

The emitters (:mod:`~mechgen.codegen.emit_numpy`, :mod:`~mechgen.codegen.emit_casadi`,
:mod:`~mechgen.codegen.emit_c`, :mod:`~mechgen.codegen.emit_c_export`) pass every piece of
text they put into a comment or docstring (the model name, the specialisation's key with its
choice values, kernel and port docs) through these on use.
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


#: C99/C11 keywords (identifiers of generated C must not be one)
C_KEYWORDS = frozenset("""auto break case char const continue default do double else enum extern float for goto if
inline int long register restrict return short signed sizeof static struct switch typedef union unsigned void volatile
while _Alignas _Alignof _Atomic _Bool _Complex _Generic _Imaginary _Noreturn _Static_assert _Thread_local""".split())
#: names the generated modules and C sources bind themselves (modules, helpers, ports, loop variables)
GENERATED_BINDINGS = frozenset({"np", "ca", "math", "SPEC", "sizes", "ins", "outs", "slots", "nb", "cnt", "ns", "e",
                                "shape", "m", "local", "mapped", "vals", "b", "i", "in", "out", "nbatch", "sqrt",
                                "pow", "INFINITY", "NAN"})
_CODE_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}\Z")
_GENERATED_PATTERN = re.compile(r"(in|out|len_in|len_out|i|ok|local)[0-9]+\Z|(mg_|build_|_)")


def code_identifier(name: object) -> str:
    """``name`` if it may be printed as a variable of generated Python or C, else ValueError.

    A local of a kernel (``g0``, ``t3`` after lowering, see :mod:`mechgen.codegen.lower`) passes;
    anything that is not a plain ASCII identifier, is a Python or C keyword, or is a name the
    generated text binds itself (:data:`GENERATED_BINDINGS`, ``in0``, ``out1``, ``mg_*`` ...) does
    not: no user text becomes a program identifier, and no identifier can rebind the module's own.
    """
    import keyword

    text = str(name)
    if (not _CODE_IDENT.match(text) or keyword.iskeyword(text) or text in C_KEYWORDS or text in GENERATED_BINDINGS
            or _GENERATED_PATTERN.match(text)):
        raise ValueError(f"internal: {text!r} is not an identifier generated code may bind")
    return text


def py_literal(value: object) -> str:
    """Python text of a JSON-like value (dict, list, tuple, str, int, finite float, bool, None).

    Strings are written by ``repr`` (a valid literal for any text); anything else, a
    non-finite float included (``inf`` is a name, not a literal), is a ValueError. The
    text is checked by evaluating it back with :func:`ast.literal_eval`.
    """
    import ast
    import math
    import pprint

    def check(v, depth=0):
        if depth > 64:
            raise ValueError("internal: a generated literal nested deeper than 64")
        if isinstance(v, float) and not math.isfinite(v):
            raise ValueError(f"internal: non-finite number {v!r} in a generated literal")
        if isinstance(v, dict):
            for k, x in v.items():
                if not isinstance(k, (str, int)):
                    raise ValueError(f"internal: key {k!r} of a generated literal")
                check(x, depth + 1)
        elif isinstance(v, (list, tuple)):
            for x in v:
                check(x, depth + 1)
        elif not (v is None or isinstance(v, (str, int, float, bool))):
            raise ValueError(f"internal: {type(v).__name__} in a generated literal")

    check(value)
    text = pprint.pformat(value, width=110, sort_dicts=True)
    if ast.literal_eval(text) != value:
        raise ValueError("internal: a generated literal does not read back")
    return text
