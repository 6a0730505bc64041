"""The one reader of the data files the command line is given: ``fit --data`` (measurements,
heating curves), ``inverse --path`` (targets), ``study --rows`` (samples) and a ``study --resume``
rows file. Whatever the bytes, the answer is a table or one line naming the file (and the line,
and the column) with what is wrong: not a file, too large, not UTF-8 text, NUL bytes, no header,
rows of the wrong length, cells that are not finite numbers.

CSV tables: comma-separated, ``#`` lines and blank lines skipped, a UTF-8 byte-order mark
allowed, the first remaining line the header.
"""
import csv
import io
import json
import math
from dataclasses import dataclass
from pathlib import Path

from .errors import ScenarioError, flag
from .text import clip

#: the largest file read [bytes]
MAX_BYTES = 100 * 2**20
#: the most rows a table may have
MAX_ROWS = 2_000_000


@dataclass
class Table:
    """A CSV file's ``header`` (column names as written) and ``rows`` (lists of cell texts, each
    as long as the header), with the file ``line`` of every row, for messages."""
    path: Path
    option: str
    header: list
    rows: list
    lines: list

    def where(self, k, column=None):
        """``OPTION: PATH line L[, column 'C']`` of row ``k`` (0-based)."""
        text = f"{self.option}: {clip(self.path, 200)} line {self.lines[k]}"
        return text if column is None else f"{text}, column {clip(self.header[column])!r}"

    def number(self, k, column):
        """The finite number in row ``k`` (0-based), ``column`` (index); one-line errors."""
        cell = self.rows[k][column].strip()
        try:
            value = float(cell)
        except ValueError:
            raise ScenarioError(f"{self.where(k, column)}: {clip(cell)!r} is not a number") from None
        if not math.isfinite(value):
            raise ScenarioError(f"{self.where(k, column)}: {clip(cell)!r} is not a finite number "
                                "(NaN and infinite values are not data)")
        return value

    def quantity(self, k, column, kind):
        """The number in row ``k``, ``column`` (index) in SI, read in the unit its header gives
        (``x [mm]``; none: SI already), of ``kind`` (``length``, ``force``, ``time``...)."""
        from .units import UNIT_OF, ureg
        value = self.number(k, column)
        unit = unit_of(self.header[column])
        if unit is None:
            return value
        try:
            return float(ureg.Quantity(value, unit).to(UNIT_OF[kind]).magnitude)
        except Exception:                           # pint: undefined unit or wrong dimension
            raise ScenarioError(f"{self.option}: column {self.header[column]!r}: [{unit}] is not a unit of {kind} "
                                f"({UNIT_OF[kind]})") from None

    def column(self, column):
        """Every row's number in ``column`` (index), as a list."""
        return [self.number(k, column) for k in range(len(self.rows))]


def read_text(path, option, what="data file"):
    """The text of a data file: one-line ScenarioErrors for a missing path, a directory, an
    unreadable file, one over :data:`MAX_BYTES`, bytes that are not UTF-8 (the line and
    offset named) and NUL bytes."""
    path = Path(path)
    label = clip(path, 200)
    try:
        if not path.exists():
            raise ScenarioError(f"{option}: {label}: no such file")
        if not path.is_file():
            raise ScenarioError(f"{option}: {label} is not a file (a {what})")
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ScenarioError(f"{option}: {label} is {size / 2**20:.0f} MiB; a {what} may be at most "
                                f"{MAX_BYTES // 2**20} MiB")
        data = path.read_bytes()
    except OSError as exc:
        raise ScenarioError(f"{option}: {label}: cannot read it ({exc.strerror or exc})") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ScenarioError(f"{option}: {label} line {line}: not UTF-8 text (byte 0x{data[exc.start]:02x} at "
                            f"offset {exc.start}); a {what} is a text file") from None
    if "\x00" in text:
        line = text[:text.index("\x00")].count("\n") + 1
        raise ScenarioError(f"{option}: {label} line {line}: a NUL byte; a {what} is a text file")
    return text


def read_table(path, option, what="CSV file", required=()):
    """A :class:`Table` of a CSV file (module docstring); ``required``: column names (before any
    ``[unit]``, case-insensitive) that must be present. One-line ScenarioErrors."""
    path = Path(path)
    text = read_text(path, option, what)
    numbered = [(k, line) for k, line in enumerate(text.splitlines(), start=1)
                if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        raise ScenarioError(f"{option}: {clip(path, 200)} is empty (a {what}: a header row, then one row per line)")
    if len(numbered) - 1 > MAX_ROWS:
        raise ScenarioError(f"{option}: {clip(path, 200)} has {len(numbered) - 1:,} rows; at most {MAX_ROWS:,}")
    try:
        parsed = list(csv.reader(io.StringIO("\n".join(line for _, line in numbered))))
    except csv.Error as exc:
        raise ScenarioError(f"{option}: {clip(path, 200)}: not a CSV table ({exc})") from None
    header, rows = [cell.strip() for cell in parsed[0]], parsed[1:]
    lines = [k for k, _ in numbered[1:]]
    table = Table(path, option, header, rows, lines)
    names = [name_of(h).lower() for h in header]
    if any(not name for name in names):
        raise ScenarioError(f"{option}: {clip(path, 200)} line {numbered[0][0]}: an empty column name in the header")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise ScenarioError(f"{option}: {clip(path, 200)} line {numbered[0][0]}: column {repeated[0]!r} appears twice")
    missing = [c for c in required if c.lower() not in names]
    if missing:
        raise ScenarioError(f"{option}: {clip(path, 200)} needs the column(s) {', '.join(missing)}; found "
                            f"{', '.join(header)}")
    for k, row in enumerate(rows):
        if len(row) != len(header):
            raise ScenarioError(f"{table.where(k)}: {len(row)} values for {len(header)} columns")
    return table


def name_of(column):
    """A header's name without its ``[unit]``: ``"tip_x [mm]"`` -> ``"tip_x"``."""
    return column.split("[")[0].strip()


def unit_of(column):
    """A header's ``[unit]`` (None when it has none)."""
    column = column.strip()
    if column.endswith("]") and "[" in column:
        return column[:-1].split("[", 1)[1].strip() or None
    return None


def read_json_lines(path, option):
    """The records of a JSON-lines file (one JSON value per line): a line that is not valid JSON
    is left out when it is the last (a write cut short by a kill) and an error otherwise; bytes
    that are not UTF-8 are an error naming the line."""
    text = read_text(path, option, "rows file")
    lines = text.splitlines()
    records = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            if number == len(lines):
                break
            raise ScenarioError(f"{option}: {clip(path, 200)} line {number}: not a JSON row; the file is damaged "
                                f"(delete it, or run without {flag('--resume')})") from None
    return records
