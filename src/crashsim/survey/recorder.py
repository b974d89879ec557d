"""Pre-crash recorder tables (CSV with a header row) read into ``[[evidence.recorder]]`` samples."""

from __future__ import annotations

import csv
import difflib
import math

from ..errors import ScenarioError

__all__ = ["read_recorder", "TIME_UNITS", "SPEED_UNITS"]

TIME_UNITS = {"s": 1.0, "ms": 1e-3}
SPEED_UNITS = {"km/h": 1 / 3.6, "kph": 1 / 3.6, "mph": 0.44704, "m/s": 1.0, "ft/s": 0.3048}
_CHANNELS = ("time", "speed", "brake", "abs", "accelerator", "steering", "yaw_rate")


def _number(text: str) -> float | None:
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
        Samples at or before the impact (time + 0 <= 0), in file order.
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
    for r, row in enumerate(reader, 2):
        if not row or not any(c.strip() for c in row):
            continue
        t = _number(row[col["time"]]) if col["time"] < len(row) else None
        v = _number(row[col["speed"]]) if col["speed"] < len(row) else None
        if t is None or v is None:
            blank += 1
            continue
        t *= TIME_UNITS[tu]
        v *= SPEED_UNITS[su]
        if t + spec["time_offset"] > 0:
            later += 1
            continue
        if v < 0:
            raise ScenarioError(f"{path}: row {r}: speed {row[col['speed']]!r} is negative", field=f"{key}.speed",
                                file=file)
        low = any(row[col[ch]].strip().lower() in on for ch in ("brake", "abs") if ch in col and col[ch] < len(row))
        samples.append((t, v, low))
    if blank:
        notes.append(f"{blank} rows without a number in the time or speed column were left out")
    if later:
        notes.append(f"{later} samples after the impact were left out (pre-crash data end at it)")
    extra = [ch for ch in ("accelerator", "steering", "yaw_rate") if ch in col]
    if extra:
        notes.append(f"channels read but not compared (no model output to check them against): {', '.join(extra)}")
    if not samples:
        raise ScenarioError(f"{path}: no pre-crash samples (time <= 0 after time_offset) with a time and a speed",
                            field=f"{key}.file", file=file)
    return samples, notes
