"""Writing the live view's values back into the user's scenario file, keeping its comments.

The file is edited with tomlkit (a TOML parser that keeps comments, order and layout): each value
the view holds replaces the value at its path, written as the view holds it (in the unit the file
used for that key); a key the file does not have is added to its table (an absent table is
added). Nothing else of the file changes.
"""

from __future__ import annotations

from typing import Any, Mapping

from ..errors import ScenarioError
from ..units import parse

__all__ = ["save_values"]


def _node(doc, steps, file: str | None, path: str):
    """The container holding the last step of ``steps`` in the tomlkit document (tables created)."""
    import tomlkit

    node = doc
    for key, index in steps[:-1]:
        if key not in node:
            node[key] = tomlkit.table()
        node = node[key]
        if index is not None:
            try:
                node = node[index]
            except (IndexError, KeyError, TypeError):
                raise ScenarioError(f"{path!r}: the file has no item {index} of {key!r}", field="save",
                                    file=file) from None
    return node


def save_values(text: str, values: Mapping[str, Any], controls: Mapping[str, Any], *, file: str | None = None) -> str:
    """``text`` (a TOML file) with ``values`` (``{path: written}``) written in at their paths.

    Only the values that differ from the file's (by their SI value) are written, so a file saved
    without a change is the same file byte for byte.
    """
    import tomlkit

    doc = tomlkit.parse(text)
    for path, written in values.items():
        c = controls[path]
        steps = c.target.steps
        node = _node(doc, steps, file, path)
        key, index = steps[-1]
        old = node.get(key) if hasattr(node, "get") else None
        if index is not None:
            if old is None or index >= len(old):
                raise ScenarioError(f"{path!r}: the file has no vector {key!r} to write into", field="save", file=file)
            cur = old[index]
            if cur is not None and parse(cur, c.kind, field=path) == parse(written, c.kind, field=path):
                continue
            old[index] = written
        else:
            if old is not None and parse(old, c.kind, field=path) == parse(written, c.kind, field=path):
                continue
            node[key] = written
    return tomlkit.dumps(doc)
