"""Total-station point files: one point a row (number, coordinates, elevation, code), CSV or TXT.

Columns
-------
``columns`` names the columns in order, one letter each: ``P`` point number, ``N`` northing,
``E`` easting, ``X``/``Y`` plane coordinates (X east, Y north), ``Z`` elevation, ``D`` the
description (code), ``-`` a column to skip. Default ``"PNEZD"`` (the usual data-collector export).
The delimiter is a comma, a tab, a semicolon or white space (found from the first data row);
quoted fields follow CSV rules (``"TFW 6"" CONC"``). A first row whose coordinates are not
numbers is a header and is skipped.

Codes and strings (line conventions)
------------------------------------
The code of a point is its description with a trailing control word removed. The control
words (any case) are ``BEG``/``B``/``ST``/``START`` (begin a new string here), ``END``/``E``
(end the string after this point) and ``CLO``/``CL``/``CLOSE`` (this point ends the string and
the string is closed back to its first point). Without control words, a string of a line code
is the run of consecutive points (in file order) with the same code; a point of another code
ends it. With ``join = "code"`` the points of a code join in file order even when points of
other codes lie between them (the habit of crews that shoot a kerb in one pass with side shots
between), until a control word ends the string. A breakline file (``breaklines``: chains of
point numbers ``12-13-14`` one a line, as bezitopo and many COGO packages write) gives the
strings instead: each chain is a string of the code of its first point, closed if it ends at
its first point.
"""

from __future__ import annotations

import csv
import io
import re

import numpy as np

from ..errors import ScenarioError
from .entities import Entity, SurveyData
from .frame import unit_scale

__all__ = ["read_points", "split_code", "CONTROL_WORDS"]

CONTROL_WORDS = {"BEG": "begin", "B": "begin", "ST": "begin", "START": "begin", "END": "end", "E": "end",
                 "CLO": "close", "CL": "close", "CLOSE": "close"}
_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def split_code(description: str) -> tuple[str, str | None]:
    """(code, control) of a point description: ``"EP END"`` -> ``("EP", "end")``; ``"--BEG"`` forms too."""
    words = description.strip().split()
    if len(words) >= 2:
        last = words[-1].lstrip("-").upper()
        if last in CONTROL_WORDS:
            return " ".join(words[:-1]), CONTROL_WORDS[last]
    return description.strip(), None


def _rows(text: str, path: str, file: str | None):
    lines = [ln for ln in text.splitlines() if ln.strip()]
    if not lines:
        raise ScenarioError(f"{path}: the point file is empty", file=file)
    first = lines[min(1, len(lines) - 1)]
    if "\t" in first:
        delim = "\t"
    elif "," in first:
        delim = ","
    elif ";" in first:
        delim = ";"
    else:
        return [ln.split() for ln in lines]
    return list(csv.reader(io.StringIO("\n".join(lines)), delimiter=delim))


def _column_letters(columns: str, file: str | None) -> str:
    """The column letters of ``columns`` (upper case, no blanks), checked: one pair N/E or X/Y, no letter twice."""
    cols = columns.upper().replace(" ", "")
    bad = set(cols) - set("PNEXYZD-")
    both = bool(set(cols) & set("NE")) and bool(set(cols) & set("XY"))
    twice = sorted({c for c in cols if c != "-" and cols.count(c) > 1})
    if both or twice:
        raise ScenarioError(f"columns = {columns!r}: " + (f"the letter {twice[0]!r} is given twice" if twice else
                            "gives both N/E and X/Y; use one pair (P, N, E, Z, D: \"PNEZD\")"),
                            field="survey.files.columns", file=file)
    if bad or not (("N" in cols and "E" in cols) or ("X" in cols and "Y" in cols)):
        raise ScenarioError(f"columns = {columns!r}: use the letters P, N, E (or X, Y), Z, D and - (skip), with N and "
                            "E or X and Y, e.g. \"PNEZD\"", field="survey.files.columns", file=file)
    return cols


def read_points(path: str, units: str, columns: str = "PNEZD", *, join: str = "run",
                breaklines: str | None = None, line_codes=None, file: str | None = None) -> SurveyData:
    """The points and strings of a total-station file, in metres.

    Parameters
    ----------
    path : str
    units : str
        Unit of the coordinates (``"m"``, ``"ft"``, ``"us_ft"``, ...).
    columns : str
        Column letters, see the module notes.
    join : {"run", "code"}
        How points of a code form strings, see the module notes.
    breaklines : str, optional
        A breakline file giving the strings as chains of point numbers.
    line_codes : callable, optional
        ``line_codes(code) -> bool``: whether a code forms strings (lines); other codes stay
        single points. Default: every code with two or more points forms strings.

    Returns
    -------
    SurveyData
        One ``"point"`` entity per point (``ref`` its number) whose code is not a line code, and one
        ``"line"`` entity per string (``ref`` its first and last point numbers).
    """
    scale = unit_scale(units, field="survey.files.units", file=file)
    cols = _column_letters(columns, file)
    try:
        with open(path, encoding="utf-8-sig", errors="replace", newline="") as fh:
            text = fh.read()
    except OSError as exc:
        raise ScenarioError(f"cannot read the point file: {exc}", file=path) from None
    rows = _rows(text, path, file)
    ix, iy = (cols.index("E"), cols.index("N")) if "E" in cols else (cols.index("X"), cols.index("Y"))
    ip = cols.index("P") if "P" in cols else None
    idd = cols.index("D") if "D" in cols else None
    data = SurveyData(path, "points", units)
    if idd is None:
        data.empty_layers = f"columns = {columns!r} has no D (description, the code) column"
    pts, numbers, codes, controls = [], [], [], []
    first_row: dict[str, int] = {}
    short = 0
    empty = 0
    no_point = []
    for r, row in enumerate(rows):
        line = r + 1
        if len(row) <= max(ix, iy):
            raise ScenarioError(f"{path}: row {line} has {len(row)} columns; columns = {columns!r} needs "
                                f"{len(cols)}", field="survey.files.columns", file=file)
        sx, sy = row[ix].strip(), row[iy].strip()
        if not sx and not sy and r > 0:
            empty += 1
            continue
        if not (_NUMBER.match(sx) and _NUMBER.match(sy)):
            if r == 0:
                data.notes.append(f"row 1 is a header: {', '.join(c.strip() for c in row)}")
                continue
            raise ScenarioError(f"{path}: row {line}: easting or x {sx!r}, northing or y {sy!r} are not numbers (columns = "
                                f"{columns!r})", field="survey.files.columns", file=file)
        if "." not in sx + sy and "e" not in (sx + sy).lower() and max(len(sx), len(sy)) > 9:
            no_point.append(f"{sx}, {sy}")
        pts.append((float(sx), float(sy)))
        short += len(row) < len(cols)
        numbers.append(row[ip].strip() if ip is not None and ip < len(row) else str(len(pts)))
        if ip is not None:
            if numbers[-1] in first_row:
                raise ScenarioError(f"{path}: rows {first_row[numbers[-1]]} and {line} have the same point number "
                                    f"{numbers[-1]!r}; a point number names one point (renumber one of them)",
                                    field="survey.files.columns", file=file)
            first_row[numbers[-1]] = line
        desc = row[idd] if idd is not None and idd < len(row) else ""
        code, ctl = split_code(desc)
        codes.append(code)
        controls.append(ctl)
    if empty:
        data.notes.append(f"{empty} rows without coordinates (raw observations?) were left out")
    if no_point:
        data.notes.append(f"{len(no_point)} points have coordinates written without a decimal point, e.g. "
                          f"({no_point[0]}): check the export's decimal setting before trusting them")
    if not pts:
        raise ScenarioError(f"{path}: no points (columns = {columns!r})", file=file)
    if short == len(pts):  # every row: a column declared that the file does not have
        n = max(len(r) for r in rows)
        raise ScenarioError(f"{path}: the rows have {n} fields where columns = {columns!r} declares {len(cols)}; "
                            "give the letters of the columns the file has (e.g. \"PNEZ\" without a code)",
                            field="survey.files.columns", file=file)
    xy = np.asarray(pts, dtype=float) * scale
    if breaklines is not None:
        index = {n: i for i, n in enumerate(numbers)}
        strings = []
        with open(breaklines, encoding="utf-8") as fh:
            for k, ln in enumerate(fh, 1):
                chain = [c.strip() for c in ln.strip().split("-") if c.strip()]
                if not chain:
                    continue
                missing = [c for c in chain if c not in index]
                if missing:
                    raise ScenarioError(f"{breaklines}: line {k}: point {missing[0]} is not in {path}",
                                        field="survey.files.breaklines", file=file)
                closed = len(chain) > 2 and chain[0] == chain[-1]
                strings.append(([index[c] for c in (chain[:-1] if closed else chain)], closed))
        in_string = {i for s, _ in strings for i in s}
        for s, closed in strings:
            data.entities.append(Entity(codes[s[0]], f"{numbers[s[0]]}-{numbers[s[-1]]}", "line", xy[s], closed,
                                        "", "breakline"))
        for i in range(len(xy)):
            if i not in in_string:
                data.entities.append(Entity(codes[i], numbers[i], "point", xy[i:i + 1], False, "", "point"))
        data.notes.append(f"{len(strings)} strings from the breakline file {breaklines}")
        return data
    counts: dict[str, int] = {}
    for c in codes:
        counts[c] = counts.get(c, 0) + 1
    is_line = line_codes if line_codes is not None else (lambda c: counts[c] >= 2)
    open_strings: dict[str, list] = {}
    order: list = []

    def close(code: str, closed: bool) -> None:
        s = open_strings.pop(code, None)
        if s:
            order.append((code, s, closed))

    for i, (code, ctl) in enumerate(zip(codes, controls)):
        if join == "run":  # a point of another code ends the run
            for other in [c for c in open_strings if c != code]:
                close(other, False)
        if not is_line(code):
            order.append((code, [i], None))
            continue
        if ctl == "begin":
            close(code, False)
        open_strings.setdefault(code, []).append(i)
        if ctl in ("end", "close"):
            close(code, ctl == "close")
    for code in list(open_strings):
        close(code, False)
    for code, s, closed in order:
        if closed is None or len(s) == 1:
            i = s[0]
            data.entities.append(Entity(code, numbers[i], "point", xy[i:i + 1], False, "", "point"))
        else:
            data.entities.append(Entity(code, f"{numbers[s[0]]}-{numbers[s[-1]]}", "line", xy[s],
                                        bool(closed) and len(s) > 2, "", "string"))
    return data
