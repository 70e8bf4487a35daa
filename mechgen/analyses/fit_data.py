"""The data of a ``fit`` analysis: named columns of numbers, inline or from a CSV file.

``data`` is either a table of equal-length arrays (``{ d = [7.1, 12.7], R = [913, 787] }``) or a
string: a CSV file path, relative to the scene file's folder (to the working directory for a
scene given as a dict, or in Python). The file is read streamed, with bounded memory, and must be a regular file
(a folder, FIFO, device or socket is refused as what it is, a FIFO never opened for blocking reads); messages
name its line and column and show at most a 10-character escaped excerpt of the one offending cell, never a
header line or a row (issue 33). The file is UTF-8 text: a header row of column names
(identifiers, each once), then one row of numbers per line, comma-separated; blank lines and
lines starting with ``#`` are skipped. Every cell is a finite number, every row has a cell per
column. The file is at most :data:`MAX_DATA_BYTES` bytes, lines of at most :data:`MAX_LINE_BYTES`, and holds at
most the safety limit ``rows`` (mechgen.scene.bounds.LIMITS, default 10^6; ``[limits] rows = ...`` raises it)
of rows, an inline table too (checked while reading: a file of 250 MB is refused after its first 10^6 rows),
and at most 2 rows + 10 000 lines in all.
A bad file, cell or column is a SceneError naming the key (``analysis[1].data``),
the file, its line and column and what was expected.
"""
from __future__ import annotations

import csv
import math
import os
import stat
from array import array
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechgen.errors import file_kind
from mechgen.scene.bounds import LIMITS, number_text
from mechgen.scene.expr import is_identifier
from mechgen.scene.values import IDENTIFIER_RULE, fail, is_number, join, listing, show, type_name

#: the largest data file read, bytes
MAX_DATA_BYTES = 256 * 1024 * 1024
#: the most columns a data set may have
MAX_COLUMNS = 1000
#: the longest line of a data file, bytes (1000 cells of 17 significant digits fit 25 times over)
MAX_LINE_BYTES = 1024 * 1024
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


#: the longest excerpt of a cell a message shows (a data file's contents are never echoed beyond it)
EXCERPT = 10
EXPECTED_FILE = "a readable UTF-8 CSV file (path relative to the scene file's folder)"


def excerpt(cell: str) -> str:
    """A short, escaped excerpt of one cell for a message: its first :data:`EXCERPT` characters, repr-escaped,
    ``…`` when cut (a file's header line or rows are never echoed whole)."""
    text = cell.strip()
    return repr(text[:EXCERPT]) + ("…" if len(text) > EXCERPT else "")


def _opened(ctx, key: str, written: str, path: Path):
    """The data file opened for reading in binary, or a SceneError: not found, or a folder, FIFO, device or
    socket named as such (opened non-blocking and checked with fstat, so a FIFO never blocks), or too large."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise fail(ctx.file, key, f"data file {show(written)} not found (looked for {path})", EXPECTED_FILE) from None
    except IsADirectoryError:
        raise fail(ctx.file, key, f"data file {show(written)} is a folder ({path})", EXPECTED_FILE) from None
    except OSError as exc:
        raise fail(ctx.file, key, f"cannot read data file {show(written)} ({exc.strerror})", EXPECTED_FILE) from None
    mode, size = (st := os.fstat(fd)).st_mode, st.st_size
    if not stat.S_ISREG(mode) or size > MAX_DATA_BYTES:
        os.close(fd)
        what = f"is {file_kind(mode)}" if not stat.S_ISREG(mode) else f"is {size} bytes"
        raise fail(ctx.file, key, f"data file {show(written)} {what} ({path})",
                   EXPECTED_FILE if not stat.S_ISREG(mode) else f"at most {MAX_DATA_BYTES} bytes")
    os.set_blocking(fd, True)
    return os.fdopen(fd, "rb")


def _lines(ctx, key: str, written: str, fh):
    """(line number, text) of the file's rows: blank and ``#`` lines skipped, decoded as UTF-8, streamed (bounded
    memory); at most :data:`MAX_DATA_BYTES` bytes and :func:`line_limit` lines in all are read."""
    read, top = 0, line_limit(ctx)
    for number, raw in enumerate(iter(lambda: fh.readline(MAX_LINE_BYTES + 1), b""), 1):
        read += len(raw)
        if len(raw) > MAX_LINE_BYTES:
            raise fail(ctx.file, key, f"line {number} of {written} is longer than {MAX_LINE_BYTES} bytes",
                       f"rows of at most {MAX_COLUMNS} numbers, one row per line")
        if read > MAX_DATA_BYTES or number > top:
            what = f"more than {MAX_DATA_BYTES} bytes" if read > MAX_DATA_BYTES else f"more than {top} lines"
            raise fail(ctx.file, key, f"data file {show(written)} has {what}",
                       f"at most {MAX_DATA_BYTES} bytes and {top} lines (blank and comment lines included; "
                       "raise [limits] rows = ...)")
        try:
            line = raw.decode("utf-8-sig" if number == 1 else "utf-8")
        except UnicodeDecodeError as exc:
            raise fail(ctx.file, key, f"line {number} of {written} is not UTF-8 text (byte {exc.start + 1} of the "
                       "line)", EXPECTED_FILE) from None
        if line.strip() and not line.lstrip().startswith("#"):
            yield number, line.rstrip("\r\n")


def line_limit(ctx) -> int:
    """The most lines a data file may have in all: twice the row limit and 10 000 more (blank lines and comments
    are skipped, but a file of nothing else must not run for minutes)."""
    return 2 * row_limit(ctx) + 10_000


def _cells(ctx, key: str, written: str, number: int, line: str) -> list[str]:
    """The comma-separated cells of one line (a quoted cell cannot span lines)."""
    try:
        return next(csv.reader((line,), strict=True))
    except csv.Error as exc:
        raise fail(ctx.file, key, f"line {number} of {written} is not CSV ({exc}; a quoted cell cannot span lines)",
                   "comma-separated numbers, one row per line") from None


def _header(ctx, key: str, written: str, cells: list[str], line: int) -> list[str]:
    names = [c.strip() for c in cells]
    if len(names) > MAX_COLUMNS:
        raise fail(ctx.file, key, f"data file {show(written)} has {len(names)} columns", f"at most {MAX_COLUMNS}")
    for j, name in enumerate(names, 1):
        if not is_identifier(name):
            raise fail(ctx.file, key, f"line {line} of {written}, column {j}: the header cell {excerpt(name)} is not "
                       "an identifier", "a header row of column names: " + IDENTIFIER_RULE)
        if name in names[: j - 1]:
            raise fail(ctx.file, key, f"line {line} of {written}, column {j}: the name {excerpt(name)} comes twice",
                       "each column name once")
    return names


def _read_csv(ctx, key: str, written: str) -> Data:
    """The columns of a CSV file: header row, then numbers; streamed (the row limit checked while reading)."""
    with _opened(ctx, key, written, _path(ctx, written)) as fh:
        rows = _lines(ctx, key, written, fh)
        first = next(rows, None)
        if first is None:
            raise fail(ctx.file, key, f"data file {show(written)} has no header row",
                       "a header row of column names, then rows of numbers")
        names = _header(ctx, key, written, _cells(ctx, key, written, *first), first[0])
        values, lines = _numbers(ctx, key, written, rows, names)
    if not lines:
        raise fail(ctx.file, key, f"data file {show(written)} has no data rows",
                   "a header row of column names, then rows of numbers")
    table = np.array(values, dtype=float).reshape(len(lines), len(names))
    return Data({n: table[:, j].copy() for j, n in enumerate(names)}, written, tuple(lines))


def _numbers(ctx, key: str, written: str, rows, names: list[str]) -> tuple[array, list[int]]:
    """The cells of the data rows as one flat array of doubles (row-major) and each row's line number; a row
    past the scene's row limit is refused as soon as it is read."""
    values, lines, top = array("d"), [], row_limit(ctx)
    for number, line in rows:
        if len(lines) == top:
            raise _too_many(ctx, key, f"data file {show(written)} has")
        cells = _cells(ctx, key, written, number, line)
        if len(cells) != len(names):
            raise fail(ctx.file, key, f"line {number} of {written} has {len(cells)} cells, the header {len(names)}",
                       "a cell per column in every row")
        for j, cell in enumerate(cells):
            try:
                value = float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise fail(ctx.file, key, f"line {number} of {written}, column '{names[j]}': {excerpt(cell)} "
                           "is not a finite number", "numeric cells")
            values.append(value)
        lines.append(number)
    return values, lines


def column(ctx, key: str, data: Data, name: str) -> np.ndarray:
    """The values of the column ``name`` (a key's value), or a SceneError listing the columns."""
    if name not in data.columns:
        where = f" of {data.source}" if data.source else ""
        names = [n if len(n) <= 40 else n[:40] + "…" for n in list(data.columns)[:8]]
        more = f" and {len(data.columns) - 8} more" if len(data.columns) > 8 else ""
        raise fail(ctx.file, key, f"no data column {show(name)}{where}", "one of the columns: " + listing(names) + more)
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
