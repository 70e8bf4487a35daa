"""How an analysis option reads in the documentation and in messages: its default (:func:`default_text`, as a
scene writes it: :func:`toml_literal`), the first sentence of its meaning, and a line's ``|`` escaped for
reStructuredText. Used by the reference pages (mechgen.analyses.reference) and by the Python API's help
(mechgen.analyses.public)."""
from __future__ import annotations

import json
import re
from typing import Any

from mechgen.analyses.schema import ABSENT, ALL_OUTPUTS, REQUIRED, Option


def escape_bars(line: str) -> str:
    """``|`` outside inline literals escaped (a docstring's |x| is a norm, not a substitution)."""
    parts = line.split("``")
    return "``".join(part if i % 2 else part.replace("|", "\\|") for i, part in enumerate(parts))


def default_text(option: Option) -> str:
    """An option's default as a reader sees it: ``required``, ``optional`` (no default), every output, or the
    value as TOML-like literal text."""
    if option.default is REQUIRED:
        return "**required**"
    if option.default is ABSENT:
        return "optional (no default)"
    if option.default is ALL_OUTPUTS:
        return "every model output"
    return f"``{toml_literal(option.default)}``"


def toml_literal(value: Any) -> str:
    """A default as a scene writes it: ``"auto"``, ``true``, ``1e-08``, ``[1.0]``, ``{ a = 1 }``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_literal(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {toml_literal(v)}" for k, v in value.items()) + " }" if value else "{}"
    return repr(value)


def first_sentence(text: str) -> str:
    """The first sentence of a meaning (up to the first full stop followed by a capital letter or the end;
    "e.g." and "i.e." do not end one), its spaces joined."""
    text = " ".join(text.split())
    match = re.search(r"(?<!e\.g)(?<!i\.e)\.(\s+(?=[A-Z`(*])|$)", text)
    return text[:match.start() + 1] if match else text
