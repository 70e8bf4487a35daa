"""The reference pages of the analysis kinds, generated from the analyses registry (reStructuredText text).

Each page comes from the objects the scene loader validates against: the kind's ``schema`` (option names,
defaults, each Option's ``doc`` as the meaning, the ``expected`` text and the check function's docstring as
what it accepts), the kind's module docstring
(what it computes) and the outputs documented in :mod:`mechgen.analyses.outputs_doc`. Nothing here imports
Sphinx; ``docs/_ext/mechgen_reference.py`` writes these strings into the documentation at build time, so
the reference and the loader cannot disagree on names or defaults.
"""
from __future__ import annotations

import importlib
import inspect
from pathlib import Path
from typing import Any

from mechgen.analyses.option_text import default_text, escape_bars
from mechgen.analyses.outputs_doc import outputs_of
from mechgen.analyses.registry import MODULES, get, kinds
from mechgen.analyses.schema import ABSENT, ALL_OUTPUTS, REQUIRED, Option

#: where a kind's page lives relative to the documentation's root (``kinds/<kind>``)
FOLDER = "kinds"


def docstring_rst(text: str | None) -> str:
    """A module docstring as reStructuredText: bars escaped, and each indented block after a blank line (the
    formulas docstrings set apart) shown as a literal block, as Python's help() shows it; an
    indented line right after text (a bullet's continuation) stays as it is."""
    lines = inspect.cleandoc(text or "").splitlines()
    out: list[str] = []
    inside = False
    for line in lines:
        indented = line.startswith(" ") and line.strip()
        follows_text = bool(out) and bool(out[-1].strip())
        if indented and not inside and follows_text:
            out.append(escape_bars(line))  # a bullet's or a definition's continuation
            continue
        if indented and not inside:
            while out and not out[-1].strip():
                out.pop()
            if out and out[-1].rstrip().endswith(":") and not out[-1].rstrip().endswith("::"):
                out[-1] = out[-1].rstrip() + ":"
            else:
                out.append("::")
            out.append("")
            inside = True
        elif line.strip() and not indented:
            if inside:
                out.append("")
            inside = False
        out.append(line if inside else escape_bars(line))
    return "\n".join(out)


def described(doc: str, name: str) -> str:
    """What a kind's module docstring says of option ``name``: the parenthesis right after its first
    ``name`` (``series`` (the time history; ...)), brackets balanced; empty when it says nothing so."""
    text = " ".join(doc.split())
    start = text.find(f"``{name}`` (")
    if start < 0:
        return ""
    i = start + len(name) + 5
    depth = 0
    for j in range(i, len(text)):
        depth += {"(": 1, ")": -1}.get(text[j], 0)
        if depth == 0:
            return text[i + 1:j]
    return ""


def first_paragraph(text: str | None) -> str:
    """The first paragraph of a docstring, its lines joined (empty for none)."""
    paragraph = inspect.cleandoc(text or "").split("\n\n")[0]
    return " ".join(line.strip() for line in paragraph.splitlines())


def check_meaning(check: Any) -> str:
    """What a check accepts: its docstring's first paragraph, or for the checks made by a factory (a choice,
    a bounded count) the values closed over; empty when neither says."""
    text = first_paragraph(getattr(check, "__doc__", None))
    if text:
        return text
    try:
        closed = inspect.getclosurevars(check).nonlocals
    except (TypeError, ValueError):
        return ""
    if "names" in closed:
        return "One of: " + ", ".join(f"``{name}``" for name in closed["names"]) + "."
    if "limit" in closed:
        return f"An integer from 1 to the safety limit ``{closed['limit']}`` (raised in a scene's ``[limits]``)."
    if "low" in closed and "high" in closed:
        return f"An integer from {closed['low']} to {closed['high']}."
    return ""


def sentence(text: str) -> str:
    """``text`` as a sentence: its first letter capitalised and a full stop at its end."""
    text = " ".join(text.split())
    if not text:
        return ""
    return text[0].upper() + text[1:] + ("" if text.endswith(".") else ".")


def option_meaning(option: Option, said: str = "") -> str:
    """An option's meaning: its ``doc`` (or, where that is empty, what the kind's docstring says of it: ``said``),
    then what its check accepts and the ``expected`` text where it says more."""
    accepts = check_meaning(option.check)
    if option.expected and option.expected != "a value" and option.expected.lower() not in accepts.lower():
        accepts = (accepts + " " if accepts else "") + f"Expected: {option.expected}."
    meaning = escape_bars(sentence(option.doc)) if option.doc else (
        f"*Described:* {escape_bars(said)}." if said else "")
    parts = [meaning, f"*Accepts:* {accepts}" if accepts else ""]
    return " ".join(p for p in parts if p) or "See the description above."


#: what a cell without content shows (a unit of "-", a dimensionless number or a label, too): an em dash, since
#: a lone "-" (or one that opens the cell) in a list-table's cell would start a nested, empty bullet list
NO_CONTENT = "\u2014"


def cell(text: str) -> str:
    """Text for one cell of a list-table (one line; an empty cell, or one of a lone "-", as an em dash, and a
    leading "- " as one too, so that no cell opens a bullet list)."""
    text = " ".join(text.split())
    if text in ("", "-"):
        return NO_CONTENT
    if text.startswith("- "):
        return NO_CONTENT + text[1:]
    return text


def table(header: tuple[str, ...], rows: list[tuple[str, ...]], widths: str) -> list[str]:
    """A reStructuredText list-table."""
    lines = [".. list-table::", "   :header-rows: 1", f"   :widths: {widths}", ""]
    for row in [header, *rows]:
        lines.append(f"   * - {cell(row[0])}")
        lines.extend(f"     - {cell(value)}" for value in row[1:])
    return lines + [""]


def module_of(kind: str) -> str:
    """The module that registers ``kind`` (a built-in kind's own module)."""
    for module in MODULES:
        if module.rsplit(".", 1)[1] == kind:
            return module
    return get(kind).run.__module__


def title(text: str, underline: str) -> list[str]:
    return [text, underline * len(text), ""]


def options_section(kind: str) -> list[str]:
    """The scene keys of ``kind``: name, default, meaning (each Option's ``doc``), from its schema."""
    schema = get(kind).schema
    if not schema:
        return title("Scene keys", "-") + ["This kind takes no options.", ""]
    doc = importlib.import_module(module_of(kind)).__doc__ or ""
    rows = [(f"``{name}``", default_text(option), option_meaning(option, "" if option.doc else described(doc, name)))
            for name, option in schema.items()]
    return title("Scene keys", "-") + table(("key", "default", "meaning"), rows, "18 18 64")


def outputs_section(kind: str) -> list[str]:
    """The outputs of ``kind`` (mechgen.analyses.outputs_doc), or a pointer to its module docstring."""
    documented = outputs_of(kind)
    head = title("Outputs", "-")
    if not documented:
        return head + [f"Not tabulated yet: see the outputs named in the description above "
                       f"(``{module_of(kind)}``).", ""]
    rows = [(f"``{o.name}``", o.shape, o.unit, o.meaning) for o in documented]
    return head + table(("name", "shape", "unit", "meaning"), rows, "18 16 16 50")


def kernels_section(kind: str) -> list[str]:
    """The kernels the kind asks the compile step for, with its default options (the kind's ``needs``)."""
    entry = get(kind)
    defaults = {name: option.default for name, option in entry.schema.items()
                if option.default not in (REQUIRED, ABSENT, ALL_OUTPUTS)}
    head = title("Kernels", "-")
    try:
        needed = sorted(entry.needs(defaults, internal=False))
    except (KeyError, TypeError, ValueError):  # a kind whose kernels are those of an inner analysis
        return head + ["Those of the analysis it runs (see the description above).", ""]
    names = ", ".join(f"``{name}``" for name in needed) or "none"
    return head + [f"Generated kernels it needs with its default options: {names} (other options may add "
                   "some: the kind's ``needs``).", ""]


def analysis_tables(text: str) -> list[str]:
    """The ``[[analysis]]`` tables of a scene's text, each from its header to the next header, trailing
    comments and blank lines left to the next table."""
    tables, current = [], None
    for line in text.splitlines():
        if line.startswith("["):
            if current is not None:
                tables.append(current)
            current = [line] if line.strip() == "[[analysis]]" else None
        elif current is not None:
            current.append(line)
    if current is not None:
        tables.append(current)
    trimmed = []
    for lines in tables:
        while lines and (not lines[-1].strip() or lines[-1].lstrip().startswith("#")):
            lines.pop()
        trimmed.append("\n".join(lines))
    return trimmed


def example_scene(kind: str, scenes: Path | None) -> tuple[str, str] | None:
    """The shortest ``[[analysis]]`` table of ``kind`` among the shipped scenes: (file name, table text)."""
    if scenes is None or not scenes.is_dir():
        return None
    found = []
    for path in sorted(scenes.glob("*.toml")):
        for table_text in analysis_tables(path.read_text(encoding="utf-8")):
            if f'\nkind = "{kind}"' in table_text:  # the table's own kind, not an inner table's
                found.append((len(table_text), path.name, table_text))
    if not found:
        return None
    _, name, table_text = min(found)
    return name, table_text


def example_section(kind: str, scenes: Path | None) -> list[str]:
    """A shipped scene's table of this kind, or a line saying no shipped scene uses the kind (nothing without a
    folder of scenes: an installed package has none)."""
    if scenes is None or not scenes.is_dir():
        return []
    found = example_scene(kind, scenes)
    if found is None:
        return title("Example", "-") + ["No shipped scene uses this kind (``scenes/*.toml``); the usage above "
                                         "shows the keys it requires.", ""]
    name, table_text = found
    lines = title("Example", "-") + [f"From the shipped scene ``scenes/{name}``:", "", ".. code-block:: toml", ""]
    return lines + [f"   {line}" if line.strip() else "" for line in table_text.splitlines()] + [""]


def usage_section(kind: str) -> list[str]:
    """How to call the kind: a scene table and the Python function."""
    required = [name for name, option in get(kind).schema.items() if option.default is REQUIRED]
    scene = ["[[analysis]]", f'name = "{kind}"', f'kind = "{kind}"'] + [f"# {name} = ...  (required)"
                                                                        for name in required]
    from mechgen.analyses import public

    python = (f":func:`mechgen.{kind}(system, ...) <mechgen.analyses.public.{kind}>`" if kind in public.__all__
              else f':func:`mechgen.analysis("{kind}", system, ...) <mechgen.analyses.public.analysis>`')
    lines = title("Usage", "-") + ["In a scene (required keys shown):", "", ".. code-block:: toml", ""]
    lines += [f"   {line}" for line in scene] + ["", f"From Python: {python}, returning a "
                                                    ":class:`mechgen.Result`.", ""]
    return lines


def kind_page(kind: str, scenes: Path | None = None) -> str:
    """The reference page of one analysis kind (reStructuredText); ``scenes``: a folder of scenes to take an
    example table from."""
    module = module_of(kind)
    doc = docstring_rst(importlib.import_module(module).__doc__)
    lines = [f".. _kind-{kind}:", ""] + title(f"``{kind}``", "=")
    lines += [doc, "", f"*Module:* ``{module}``.", ""]
    lines += options_section(kind) + outputs_section(kind) + kernels_section(kind) + usage_section(kind)
    lines += example_section(kind, scenes)
    return "\n".join(lines)


def index_page() -> str:
    """The page listing every kind, with a toctree of their pages."""
    lines = title("Analysis kinds", "=")
    lines += ["One page per analysis kind, generated from the analyses registry (``mechgen.analyses.registry``) "
              "and the schemas the scene loader validates against.", ""]
    rows = [(f":ref:`{kind} <kind-{kind}>`", first_paragraph(importlib.import_module(module_of(kind)).__doc__))
            for kind in kinds()]
    lines += table(("kind", "what it computes"), rows, "20 80")
    lines += [".. toctree::", "   :hidden:", ""] + [f"   {kind}" for kind in kinds()] + [""]
    return "\n".join(lines)


def pages(scenes: Path | None = None) -> dict[str, str]:
    """Every generated page: file name (``index.rst``, ``<kind>.rst``) -> text; ``scenes``: the shipped scenes'
    folder for the examples (left out: no example sections)."""
    return {"index.rst": index_page(), **{f"{kind}.rst": kind_page(kind, scenes) for kind in kinds()}}
