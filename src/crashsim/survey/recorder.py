"""Pre-crash recorder tables (CSV with a header row) read into ``[[evidence.recorder]]`` samples."""

from __future__ import annotations

import csv
import difflib
import math
import re

from ..errors import ScenarioError

__all__ = ["read_recorder", "TIME_UNITS", "SPEED_UNITS"]

TIME_UNITS = {"s": 1.0, "ms": 1e-3}
SPEED_UNITS = {"km/h": 1 / 3.6, "kph": 1 / 3.6, "mph": 0.44704, "m/s": 1.0, "ft/s": 0.3048}
_CHANNELS = ("time", "speed", "brake", "abs", "accelerator", "steering", "yaw_rate")


#: Largest |time_offset| the schema allows [s]: a sample up to this far after the file's impact
#: can be brought before it by a fitted offset, so it is kept (and compared only when it is).
OFFSET_RANGE = 5.0
_DECIMAL_COMMA = re.compile(r"^\s*[-+]?\d+,\d+\s*$")


def _number(text: str, comma: bool = False) -> float | None:
    if comma and _DECIMAL_COMMA.match(text or ""):
        text = text.replace(",", ".")
    try:
        x = float(text)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def read_recorder(path: str, spec: dict, *, key: str = "survey.recorders[0]", file: str | None = None):
    """The samples of a recorder table.

    Parameters
    ----------
    path : str
    spec : dict
        The validated ``[[survey.recorders]]`` entry (column names, units, ``on`` values).

    Returns
    -------
    samples : list of (time [s], speed [m/s], lower_bound: bool)
        Samples up to :data:`OFFSET_RANGE` after the impact, in file order (those after it with
        the file's ``time_offset`` are compared only when a fitted offset brings them before it).
    notes : list of str
        Rows left out and why, channels found.
    """
    tu, su = spec["time_unit"].strip(), spec["speed_unit"].strip()
    if tu not in TIME_UNITS:
        raise ScenarioError(f"{path}: time_unit = {tu!r}; allowed {', '.join(TIME_UNITS)}", field=f"{key}.time_unit",
                            file=file)
    if su not in SPEED_UNITS:
        raise ScenarioError(f"{path}: speed_unit = {su!r}; allowed {', '.join(SPEED_UNITS)}",
                            field=f"{key}.speed_unit", file=file)
    on = {w.strip().lower() for w in spec["on"].split(",") if w.strip()}
    try:
        with open(path, encoding="utf-8-sig", errors="replace", newline="") as fh:
            text = fh.read()
    except OSError as exc:
        raise ScenarioError(f"cannot read the recorder table: {exc}", field=f"{key}.file", file=file) from None
    sample = text[:4096]
    try:
        dialect = csv.Sniffer().sniff(sample, delimiters=",;\t")
    except csv.Error:
        dialect = csv.excel
    reader = csv.reader(text.splitlines(), dialect)
    header = next(reader, None)
    if not header:
        raise ScenarioError(f"{path}: the recorder table is empty", field=f"{key}.file", file=file)
    header = [h.strip() for h in header]
    col = {}
    for ch in _CHANNELS:
        name = spec.get(ch)
        if name is None:
            continue
        if name.strip() not in header:
            near = difflib.get_close_matches(name.strip(), header, n=1, cutoff=0.4)
            hint = f"; nearest: {near[0]!r}" if near else ""
            raise ScenarioError(f"{path} has no column {name!r}{hint}. Columns: {', '.join(map(repr, header))}",
                                field=f"{key}.{ch}", file=file)
        col[ch] = header.index(name.strip())
    samples, notes = [], []
    later = blank = 0
    rows = [(r, row) for r, row in enumerate(reader, 2) if row and any(c.strip() for c in row)]
    if not rows:
        raise ScenarioError(f"{path}: the recorder table has a header row but no data rows", field=f"{key}.file",
                            file=file)
    # a decimal comma ("-15,0") where the columns are not separated by commas: read as a decimal point, said so
    comma = dialect.delimiter != "," and any(_DECIMAL_COMMA.match(row[col[ch]]) for _, row in rows
                                              for ch in ("time", "speed") if col[ch] < len(row))
    seen: dict[float, int] = {}
    for r, row in rows:
        t = _number(row[col["time"]], comma) if col["time"] < len(row) else None
        v = _number(row[col["speed"]], comma) if col["speed"] < len(row) else None
        if t is None or v is None:
            if dialect.delimiter == "," and len(row) > len(header):
                raise ScenarioError(f"{path}: row {r} has {len(row)} fields where the header has {len(header)}: "
                                    "a decimal comma in a comma-separated table? (write 15.0, or separate the "
                                    "columns with ';')", field=f"{key}.file", file=file)
            blank += 1
            continue
        t *= TIME_UNITS[tu]
        v *= SPEED_UNITS[su]
        if t in seen:
            raise ScenarioError(f"{path}: rows {seen[t]} and {r} have the same time {row[col['time']].strip()!r} "
                                f"{tu}; a recorder takes one sample at a time", field=f"{key}.time", file=file)
        seen[t] = r
        if t > OFFSET_RANGE:
            later += 1
            continue
        if v < 0:
            raise ScenarioError(f"{path}: row {r}: speed {row[col['speed']]!r} is negative", field=f"{key}.speed",
                                file=file)
        low = any(row[col[ch]].strip().lower() in on for ch in ("brake", "abs") if ch in col and col[ch] < len(row))
        samples.append((t, v, low))
    if comma:
        notes.append("decimal commas (\"-15,0\") read as decimal points")
    if blank:
        notes.append(f"{blank} rows without a number in the time or speed column were left out")
    if later:
        notes.append(f"{later} samples more than {OFFSET_RANGE:g} s after the impact were left out")
    after = sum(t + spec["time_offset"] > 0 for t, _, _ in samples)
    if after:
        notes.append(f"{after} samples after the impact with time_offset = {spec['time_offset']:g} s are kept but "
                     "not compared (a fitted time_offset can bring them before it)")
    extra = [ch for ch in ("accelerator", "steering", "yaw_rate") if ch in col]
    if extra:
        notes.append(f"channels read but not compared (no model output to check them against): {', '.join(extra)}")
    if not any(t + spec["time_offset"] <= 0 for t, _, _ in samples):
        raise ScenarioError(f"{path}: no pre-crash samples (time <= 0 after time_offset) with a time and a speed",
                            field=f"{key}.file", file=file)
    return samples, notes
