"""The survey sources of a scene, as text for the report and as JSON records."""

from __future__ import annotations

__all__ = ["survey_records", "format_survey"]


def survey_records(scenario) -> list[dict]:
    """The ``survey.imported`` records of a loaded scenario (empty without a survey)."""
    data = getattr(scenario, "data", None)
    s = data.get("survey") if isinstance(data, dict) else None
    return list(s.get("imported") or []) if isinstance(s, dict) else []


def format_survey(records: list[dict]) -> str:
    """One line per imported item (its target, kind, file, layer or code, handle or point numbers),
    then the notes and warnings of the import."""
    items = [r for r in records if r["kind"] not in ("note", "label", "ignore", "underlay", "warning")]
    notes = [r for r in records if r["kind"] == "note"]
    labels = [r for r in records if r["kind"] == "label"]
    ignored = [r for r in records if r["kind"] == "ignore"]
    lines = [f"Survey sources ({len(items)} items imported)"]
    rows = [(r["target"] or "(left out)", r["kind"], r["file"], r["layer"], f"{r['type']} {r['ref']}".strip(),
             r["note"]) for r in items]
    if rows:
        w = [max(len(row[i]) for row in rows) for i in range(5)]
        for row in rows:
            lines.append("  " + "  ".join(row[i].ljust(w[i]) for i in range(5)).rstrip()
                         + (f"  {row[5]}" if row[5] else ""))
    if labels:
        lines.append(f"  labels: {len(labels)} texts named the items nearest them")
    if ignored:
        lines.append(f"  ignored on purpose (kind = \"ignore\"): {len(ignored)} entities")
    for r in notes:
        lines.append(f"  note, {r['file']}: {r['note']}")
    for r in records:
        if r["kind"] == "warning":
            lines.append(f"  warning: {r['note']}")
    for r in records:
        if r["kind"] == "underlay":
            lines.append(f"  underlay, {r['file']}: {r['note']}")
    return "\n".join(lines)
