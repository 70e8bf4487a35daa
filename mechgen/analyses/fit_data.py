"""The data of a ``fit`` analysis: named columns of numbers, inline or from a CSV file.

``data`` is either a table of equal-length arrays (``{ d = [7.1, 12.7], R = [913, 787] }``) or a
string: a CSV file path, relative to the scene file's folder (to the working directory for a
scene given as a dict, or in Python). The file is UTF-8 text: a header row of column names
(identifiers, each once), then one row of numbers per line, comma-separated; blank lines and
lines starting with ``#`` are skipped. Every cell is a finite number, every row has a cell per
column. The file is at most :data:`MAX_DATA_BYTES` bytes and holds at most the safety limit
``rows`` (mechgen.scene.bounds.LIMITS, default 10^6; ``[limits] rows = ...`` raises it) of rows, an
inline table too. A bad file, cell or column is a SceneError naming the key (``analysis[1].data``),
the file, its line and column and what was expected.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechgen.scene.bounds import LIMITS, number_text
from mechgen.scene.expr import is_identifier
from mechgen.scene.values import IDENTIFIER_RULE, fail, is_number, join, listing, show, type_name

#: the largest data file read, bytes
MAX_DATA_BYTES = 256 * 1024 * 1024
#: the most columns a data set may have
MAX_COLUMNS = 1000
TABLE = "a table of equal-length arrays of numbers (column = [values]) or a CSV file path"


@dataclass(frozen=True)
class Data:
    """Columns of a fit's data: name -> values (float arrays, one entry per row), in the order given.

    ``source``: the file as the scene wrote it (None: an inline table); ``lines``: each row's line
    in that file (for messages).
    """

    columns: dict
    source: str | None = None
    lines: tuple[int, ...] = ()

    @property
    def rows(self) -> int:
        """The number of rows."""
        return len(next(iter(self.columns.values())))

    def where(self, row: int, column: str | None = None) -> str:
        """Row ``row`` (0-based) as a message names it: ``line 5 of data.csv`` or ``row 3``."""
        at = f"line {self.lines[row]} of {self.source}" if self.source else f"row {row + 1}"
        return f"{at}, column '{column}'" if column else at


def row_limit(ctx) -> int:
    """The scene's safety limit on the number of rows."""
    return ctx.limits.get("rows", LIMITS["rows"])


def _too_many(ctx, key: str, what: str) -> Exception:
    top = row_limit(ctx)
    return fail(ctx.file, key, f"{what} more than {number_text(top)} rows",
                f"at most {top} rows (the limit guards against typos: raise it with [limits] rows = ... in the scene)")


def load(ctx, key: str, value: object) -> Data:
    """The ``data`` option: an inline table, or a CSV file read now (relative to the scene's folder)."""
    if isinstance(value, str):
        return _read_csv(ctx, key, value)
    if not isinstance(value, dict) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}" if not isinstance(value, dict) else "empty table",
                   TABLE)
    if len(value) > MAX_COLUMNS:
        raise fail(ctx.file, key, f"the table has {len(value)} columns", f"at most {MAX_COLUMNS} columns")
    columns: dict[str, np.ndarray] = {}
    for name, items in value.items():
        sub = join(key, name)
        if not is_identifier(name):
            raise fail(ctx.file, sub, f"column name {show(name)} is not an identifier", IDENTIFIER_RULE)
        if not isinstance(items, list) or not items:
            raise fail(ctx.file, sub, "empty array" if items == [] else f"value is {type_name(items)}",
                       "a non-empty array of numbers")
        if len(items) > row_limit(ctx):
            raise _too_many(ctx, sub, f"column '{name}' has")
        for i, item in enumerate(items, 1):
            if not is_number(item) or not np.isfinite(float(item)):
                raise fail(ctx.file, f"{sub}[{i}]", f"value is {show(item) if is_number(item) else type_name(item)}",
                           "a finite number")
        columns[name] = np.array(items, dtype=float)
    lengths = {n: len(c) for n, c in columns.items()}
    first = next(iter(lengths))
    for name, size in lengths.items():
        if size != lengths[first]:
            raise fail(ctx.file, join(key, name), f"column '{name}' has {size} values, column '{first}' has "
                       f"{lengths[first]}", "columns of equal length (one value per row)")
    return Data(columns)


def _path(ctx, text: str) -> Path:
    path = Path(text)
    if path.is_absolute():
        return path
    base = Path(ctx.file).resolve().parent if ctx.file and ctx.file != "<dict>" else Path.cwd()
    return base / path


def _text(ctx, key: str, written: str, path: Path) -> str:
    """The file's text, or a SceneError saying why not."""
    expected = "a readable UTF-8 CSV file (path relative to the scene file's folder)"
    try:
        if not path.is_file():
            raise fail(ctx.file, key, f"data file {show(written)} not found (looked for {path})", expected)
        size = path.stat().st_size
        if size > MAX_DATA_BYTES:
            raise fail(ctx.file, key, f"data file {show(written)} is {size} bytes", f"at most {MAX_DATA_BYTES} bytes")
        raw = path.read_bytes()
    except OSError as exc:
        raise fail(ctx.file, key, f"cannot read data file {show(written)} ({exc.strerror})", expected) from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise fail(ctx.file, key, f"data file {show(written)} is not UTF-8 text (byte {exc.start})", expected) from None


def _header(ctx, key: str, written: str, cells: list[str], line: int) -> list[str]:
    names = [c.strip() for c in cells]
    if len(names) > MAX_COLUMNS:
        raise fail(ctx.file, key, f"data file {show(written)} has {len(names)} columns", f"at most {MAX_COLUMNS}")
    for j, name in enumerate(names, 1):
        if not is_identifier(name):
            raise fail(ctx.file, key, f"line {line} of {written}: column {j} name {show(name)} is not an identifier",
                       "a header row of column names: " + IDENTIFIER_RULE)
        if name in names[: j - 1]:
            raise fail(ctx.file, key, f"line {line} of {written}: column '{name}' is named twice",
                       "each column name once")
    return names


def _read_csv(ctx, key: str, written: str) -> Data:
    """The columns of a CSV file: header row, then numbers."""
    text = _text(ctx, key, written, _path(ctx, written))
    lines = [(i, line) for i, line in enumerate(text.splitlines(), 1) if line.strip() and not line.lstrip().startswith("#")]
    if len(lines) < 2:
        raise fail(ctx.file, key, f"data file {show(written)} has " + ("no header row" if not lines else "no data rows"),
                   "a header row of column names, then rows of numbers")
    if len(lines) - 1 > row_limit(ctx):
        raise _too_many(ctx, key, f"data file {show(written)} has")
    reader = csv.reader(line for _, line in lines)
    try:
        rows = list(reader)
    except csv.Error as exc:
        raise fail(ctx.file, key, f"line {lines[reader.line_num - 1][0]} of {written} is not CSV ({exc})",
                   "comma-separated numbers") from None
    if len(rows) != len(lines):
        raise fail(ctx.file, key, f"data file {show(written)} has a quoted cell spanning lines",
                   "one row per line")
    names = _header(ctx, key, written, rows[0], lines[0][0])
    values = np.empty((len(rows) - 1, len(names)))
    for r, cells in enumerate(rows[1:]):
        line = lines[r + 1][0]
        if len(cells) != len(names):
            raise fail(ctx.file, key, f"line {line} of {written} has {len(cells)} cells, the header "
                       f"{len(names)} ({listing(names)})", "a cell per column in every row")
        for j, cell in enumerate(cells):
            try:
                number = float(cell)
            except ValueError:
                number = None
            if number is None or not np.isfinite(number):
                raise fail(ctx.file, key, f"line {line} of {written}, column '{names[j]}': {show(cell.strip())} "
                           "is not a finite number", "numeric cells")
            values[r, j] = number
    return Data({n: values[:, j].copy() for j, n in enumerate(names)}, written, tuple(i for i, _ in lines[1:]))


def column(ctx, key: str, data: Data, name: str) -> np.ndarray:
    """The values of the column ``name`` (a key's value), or a SceneError listing the columns."""
    if name not in data.columns:
        where = f" of {data.source}" if data.source else ""
        raise fail(ctx.file, key, f"no data column {show(name)}{where}", "one of the columns: " + listing(list(data.columns)))
    return data.columns[name]


def groups(values: np.ndarray | None, rows: int) -> list[tuple[float | None, np.ndarray]]:
    """(group value, row indices) for each distinct value in first-appearance order; one group of every row
    (value None) without a group column."""
    if values is None:
        return [(None, np.arange(rows))]
    order: dict[float, list[int]] = {}
    for i, v in enumerate(values):
        order.setdefault(float(v), []).append(i)
    return [(v, np.array(idx)) for v, idx in order.items()]
