"""The Monte Carlo band of the live view, run in worker processes.

A worker builds one :class:`BandRunner` per scene (keyed by the file's hash and the inputs) and
runs the samples it is sent: each sample's scene to rest (the lean result a Monte Carlo sample
reads), returning its CG paths, rest poses and whether it meets all the evidence.
"""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np

from ..errors import CrashsimError
from ..reconstruct.inputs import Scene

__all__ = ["BandRunner", "run_band_chunk", "band_worker_init", "PATH_POINTS"]

#: Points per CG path of a band sample.
PATH_POINTS = 60

_RUNNERS: dict = {}

#: Seconds between a band worker's looks at whether the server that started it still runs.
PARENT_POLL = 0.5


def band_worker_init(parent: int) -> None:
    """Start of a band worker process: Ctrl+C is the server's to handle (it stops the workers; a
    worker's own KeyboardInterrupt would only print its traceback), and the worker ends itself once
    the server process ``parent`` is gone (killed, or stopped by a signal that left no time to stop
    the workers), instead of running on as an orphan."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)

    def watch():
        while os.getppid() == parent:
            time.sleep(PARENT_POLL)
        os._exit(0)

    threading.Thread(target=watch, name="crashsim-band-parent-watch", daemon=True).start()


class BandRunner:
    """The samples of one scene: its inputs by path, built once (:class:`~crashsim.reconstruct.inputs.SceneInputs`)."""

    def __init__(self, payload: dict):
        self.inputs = Scene(payload["data"], engine=payload["engine"], file=payload["file"]).inputs(
            payload["paths"], field="uncertainty.inputs", cache=1)

    def run(self, x) -> dict:
        t0 = time.process_time()
        try:
            scene = self.inputs.run(x, lean=True)
        except CrashsimError as exc:
            return {"error": f"{type(exc).__name__}: {exc}", "cpu": time.process_time() - t0}
        cpu = time.process_time() - t0  # the sample's scene build and physics, CPU seconds
        paths, rest = {}, {}
        for r in (scene.runout or {}).values():
            for name, b in r.bodies.items():
                rest[name] = [round(float(b.rest_position[0]), 4), round(float(b.rest_position[1]), 4),
                              round(float(b.rest_heading), 5)]
        t_end = float(scene.t_end or 0.0)
        if t_end > 0:
            h = scene.history(max(t_end / (PATH_POINTS - 1), 1e-3))
            for name in rest:
                if f"{name}.x" in h:
                    paths[name] = np.round(np.column_stack([h[f"{name}.x"], h[f"{name}.y"]]), 3).tolist()
        ev = scene.evidence
        return {"paths": paths, "rest": rest, "at_rest": bool(scene.at_rest), "cpu": cpu,
                "all_passed": bool(ev.all_passed) if ev is not None else False}


def run_band_chunk(payload: dict, rows: list) -> list[dict]:
    """Run the band samples ``rows`` (SI values of ``payload['paths']``) in this process."""
    r = _RUNNERS.get(payload["key"])
    if r is None:
        _RUNNERS.clear()
        r = _RUNNERS[payload["key"]] = BandRunner(payload)
    return [r.run(x) for x in rows]
