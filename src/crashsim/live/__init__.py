"""The live reconstruction view: ``crashsim live FILE``, or :func:`crashsim.live.open_live` in Python.

Drag a vehicle, turn its heading, move the point of impact, set a speed, a coefficient or a
friction, and the whole scene is recomputed (the compiled engine), its paths, evidence verdicts,
delta-v, energy ledger and warnings redrawn, and, with ``[uncertainty]``, a Monte Carlo band of
rest positions and paths refreshed once the change comes to rest. The values go back into the
file, in its own units, with its comments kept.

Modules: :mod:`~crashsim.live.session` (the scene and its inputs: no web code),
:mod:`~crashsim.live.view` (the JSON the page draws), :mod:`~crashsim.live.band` (the band's
samples, in worker processes), :mod:`~crashsim.live.savefile` (the file written back),
:mod:`~crashsim.live.server` (the local web server: aiohttp, the ``live`` extra).
"""

from __future__ import annotations

from .._lazy import lazy_exports as _lazy_exports

__all__ = ["LiveSession", "LiveServer", "open_live"]

# aiohttp and tomlkit (the ``live`` extra) load with the server, not with this package
__getattr__, __dir__ = _lazy_exports(__name__, {"LiveSession": ".session", "LiveServer": ".server",
                                                "open_live": ".server"})
