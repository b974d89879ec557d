"""The best fit written into the user's own file: its values replaced in place, nothing else changed.

``crashsim fit --write-best OUT.toml`` hands the reconstruction to the other side's expert, so
the file written is the input file as its author wrote it: comments, key order and layout kept
(tomlkit edits the document, it does not re-serialise a dict), the ``[survey]`` a reference to its
files (never the imported items inlined), and every file path rewritten relative to the written
file, so that the folder can be moved. Only these change:

- each unknown's value at its path, in the unit of the value it replaces (an unknown that names
  an item the survey generated, ``evidence.recorder[i].time_offset`` of a recorder table, is
  written at the ``[[survey.recorders]]`` entry it came from; one the file does not hold, a
  preset's value, is added at its path);
- ``runout.engine`` where the fit's engine differs from the file's;
- the ``[fit]`` table is removed (it follows as comments at the end), and a header comment names
  what wrote the file, the best values and chi^2.
"""

from __future__ import annotations

import os
from pathlib import Path

import tomlkit

from ..errors import ScenarioError
from .overrides import get_value, resolve_path

__all__ = ["edit_best", "SURVEY_PATH_KEYS"]

#: Keys of ``[survey]`` tables that name a file (relative to the scenario file).
SURVEY_PATH_KEYS = ("file", "breaklines", "image", "world_file")


def _written_at(doc, steps: tuple, typed_recorders: int):
    """The steps at which the user's document holds (or should hold) a path's value: a recorder item
    the survey generated maps to its ``[[survey.recorders]]`` entry."""
    if len(steps) >= 3 and steps[0] == ("evidence", None) and steps[1][0] == "recorder" and steps[1][1] is not None:
        i = steps[1][1]
        if i >= typed_recorders:
            return (("survey", None), ("recorders", i - typed_recorders)) + tuple(steps[2:])
    return tuple(steps)


def _put(doc, steps: tuple, value, path: str) -> None:
    node = doc
    for depth, (key, index) in enumerate(steps[:-1]):
        if key not in node:
            if index is not None:
                raise ScenarioError(f"the input file has no {key}[{index}]; {path!r} cannot be written into it",
                                    field="--write-best")
            node[key] = tomlkit.table()
        node = node[key]
        if index is not None:
            node = node[index]
    key, index = steps[-1]
    if index is None:
        _set_in_table(node, key, value) if hasattr(node, "value") else node.__setitem__(key, value)
    else:
        node[key][index] = value


def _set_in_table(table, key: str, value) -> None:
    """``table[key] = value``; a new key goes after the table's last value, not after the comments
    that introduce the next table."""
    if key in table:
        table[key] = value
        return
    keys = [k for k, _ in table.value.body if k is not None]
    try:
        table.value._insert_after(keys[-1], key, tomlkit.item(value))  # tomlkit's own insertion
    except (AttributeError, IndexError, TypeError):  # pragma: no cover - another tomlkit
        table[key] = value


def _rebase(doc, source: Path, out: Path) -> None:
    """Every file path of ``[survey]`` relative to the written file's folder."""
    src_dir, out_dir = source.resolve().parent, out.resolve().parent

    def fix(table):
        for k in SURVEY_PATH_KEYS:
            v = table.get(k)
            if isinstance(v, str) and v:
                p = Path(v).expanduser()
                absolute = p if p.is_absolute() else src_dir / p
                table[k] = Path(os.path.relpath(absolute.resolve(), out_dir)).as_posix()

    s = doc.get("survey")
    if s is None:
        return
    for arr in ("files", "recorders"):
        for t in s.get(arr, []):
            fix(t)
    if "underlay" in s:
        fix(s["underlay"])


def edit_best(source: Path, out: Path, best: dict, unknown_paths, *, engine: str | None, header: str,
              trailer: str) -> str:
    """The text of the input file ``source`` with the best values of ``best`` (the raw best-fit dict,
    :meth:`~crashsim.reconstruct.fit.FitResult.best_scenario_dict`) written in at ``unknown_paths``,
    the engine set, ``[fit]`` removed and the paths relative to ``out``; ``header`` and ``trailer``
    are comment blocks put before and after it."""
    text = source.read_text(encoding="utf-8")
    doc = tomlkit.parse(text)
    typed = len(((doc.get("evidence") or {}).get("recorder")) or [])
    for path in unknown_paths:
        t = resolve_path(path)
        value = get_value(best, t)
        if value is None:
            raise ScenarioError(f"the best fit has no value at {path!r}", field="--write-best")
        _put(doc, _written_at(doc, t.steps, typed), value, path)
    if engine is not None:
        runout = doc.get("runout")
        if runout is not None and runout.get("engine", "scipy") != engine:
            _set_in_table(runout, "engine", engine)
    if "fit" in doc:
        del doc["fit"]
    _rebase(doc, source, out)
    body = tomlkit.dumps(doc).rstrip("\n") + "\n"
    return header + body + trailer
