"""One place for running many scene evaluations: serial, a process pool or a Dask cluster.

Monte Carlo (:mod:`crashsim.reconstruct.montecarlo`), the posterior
(:mod:`crashsim.reconstruct.posterior`) and the fit (:mod:`crashsim.reconstruct.fit`) all hand
their work to an :class:`Executor`; it chooses the backend, builds each worker's state once,
sends work in chunks, collects the results and closes what it opened.  :class:`Progress` is the
one progress display (a tqdm bar on stderr, a callback, or nothing), and :func:`child_seed` the one
rule for the random streams.

How a worker gets its state
---------------------------
A caller gives a ``factory`` and a ``payload`` (both picklable: the factory a module-level
function).  Every process or Dask worker calls ``factory(payload)`` before its first task and the
factory keeps what it builds (the scene, the fit problem; the factories cache per thread, keyed by
the payload's hash).  A task is ``fn(state, item)`` with ``fn`` a module-level function.  In this
process (``"serial"``) the state is ``local`` when given (the caller's object, already built),
else ``factory(payload)``.

Processes are forked where the platform can (the parent's compiled kernels and imported modules
are inherited, not loaded again); Dask workers receive the payload once (scattered, broadcast).

Reproducibility
---------------
A task's result depends only on its item and the payload, never on the backend, the number of
workers, the chunk size or the order in which chunks finish: the same seed gives the same numbers
serial, on processes and on Dask (tests/reconstruct/test_parallel.py).
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import sys
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from ..errors import ScenarioError
from ..outputs import check_workers

__all__ = ["BACKENDS", "Executor", "Progress", "child_seed", "chunks", "chunk_size", "choose_backend"]

#: Where the work runs.
BACKENDS = ("serial", "processes", "dask")

#: Largest chunk of samples sent to a worker at once.
MAX_CHUNK = 64


def child_seed(seed: int, key: int) -> np.random.SeedSequence:
    """The random stream ``key`` of a run with ``seed``: ``SeedSequence(seed, spawn_key=(key,))``,
    the ``key``-th child of ``SeedSequence(seed).spawn``; it depends on ``(seed, key)`` only."""
    return np.random.SeedSequence(int(seed), spawn_key=(int(key),))


def chunks(items: Sequence, size: int) -> list[list]:
    """``items`` cut into consecutive lists of ``size`` (the last one shorter)."""
    items = list(items)
    return [items[k:k + size] for k in range(0, len(items), size)]


def chunk_size(n: int, workers: int, given: int | None = None) -> int:
    """``given``, else about four chunks per worker, at most :data:`MAX_CHUNK` items and at least 1."""
    return given or max(1, min(MAX_CHUNK, math.ceil(n / (4 * workers))))


def choose_backend(workers: int | None, dask_address: Any = None, n_tasks: int | None = None) -> tuple[str, int]:
    """``(backend, workers)``: Dask when an address (or client) is given (workers counted when it
    connects, 0 until then); else processes when more than one worker and more than one task,
    else serial.  ``workers`` None: all cores."""
    if dask_address is not None:
        return "dask", 0
    nw = check_workers(workers) or (os.cpu_count() or 1)
    if nw > 1 and (n_tasks is None or n_tasks > 1):
        return "processes", nw
    return "serial", nw


# ------------------------------------------------------------------------- worker side
_STATE: dict = {}


def _init(factory, payload) -> None:
    _STATE["factory"], _STATE["payload"] = factory, payload


def _state():
    return _STATE["factory"](_STATE["payload"])


def _task(fn, item):
    return fn(_state(), item)


def _chunk_task(fn, items):
    state = _state()
    return [fn(state, item) for item in items]


def _dask_chunk(factory, fn, payload, items):
    state = factory(payload)
    return [fn(state, item) for item in items]


class Executor:
    """Runs ``fn(state, item)`` over items on one backend (see the module docstring).

    Parameters
    ----------
    factory : callable
        ``factory(payload)`` -> a worker's state (module-level, picklable).
    payload : dict
        What a worker needs to build its state (picklable).
    backend : {"serial", "processes", "dask"}
    workers : int
        Processes (``"processes"``); ignored otherwise.
    dask_address : str or distributed.Client, optional
        The cluster (``"dask"``): a client given is kept open, one made from an address is closed.
    local : object, optional
        The state of this process (``"serial"``), if already built.

    Use it as a context manager (it closes the pool or the client it opened).
    """

    def __init__(self, factory: Callable, payload: dict, backend: str = "serial", workers: int = 1, *,
                 dask_address: Any = None, local: Any = None):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        self.factory, self.payload, self.backend = factory, payload, backend
        self.workers = max(1, int(workers)) if backend != "dask" else 0
        self._local = local
        self._pool = None
        self._client = None
        self._own = False
        self._remote = None
        if backend == "processes":
            ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx, initializer=_init,
                                             initargs=(factory, payload))
        elif backend == "dask":
            try:
                from distributed import Client
            except ImportError as exc:  # pragma: no cover - depends on the environment
                raise ScenarioError("--dask needs dask.distributed (pip install distributed)", field="dask") from exc
            self._own = not isinstance(dask_address, Client)
            self._client = Client(dask_address) if self._own else dask_address
            try:
                self.workers = max(1, sum(w.get("nthreads", 1)
                                          for w in self._client.scheduler_info()["workers"].values()))
                self._remote = self._client.scatter([payload], broadcast=True)[0]
            except BaseException:
                self.close()
                raise

    # ---------------------------------------------------------------- this process
    @property
    def local(self):
        """The state of this process (built on first use when not given)."""
        if self._local is None:
            self._local = self.factory(self.payload)
        return self._local

    # ---------------------------------------------------------------- work
    def map(self, fn: Callable, items: Sequence, chunksize: int = 1) -> list:
        """``[fn(state, item) for item in items]``, in the order of ``items``."""
        items = list(items)
        if self.backend == "serial":
            state = self.local
            return [fn(state, item) for item in items]
        parts = chunks(items, max(1, int(chunksize)))
        if self.backend == "processes":
            out = []
            for part in self._pool.map(_chunk_task, [fn] * len(parts), parts):
                out.extend(part)
            return out
        futures = [self._client.submit(_dask_chunk, self.factory, fn, self._remote, p, pure=False) for p in parts]
        try:
            return [r for part in self._client.gather(futures) for r in part]
        except BaseException:
            self._client.cancel(futures)
            raise

    def submit_each(self, fn: Callable, items: Sequence) -> Iterator:
        """``fn(state, item)`` for every item, yielded in the order of ``items`` as each is ready
        (one task per item: for few long tasks, such as a fit's local starts)."""
        items = list(items)
        if self.backend == "serial":
            state = self.local
            for item in items:
                yield fn(state, item)
            return
        if self.backend == "processes":
            futures = [self._pool.submit(_task, fn, item) for item in items]
            for fut in futures:
                yield fut.result()
            return
        futures = [self._client.submit(_dask_chunk, self.factory, fn, self._remote, [item], pure=False)
                   for item in items]
        for fut in futures:
            yield fut.result()[0]

    def as_completed(self, fn: Callable, parts: Sequence[Sequence]) -> Iterator[list]:
        """``[fn(state, item) for item in part]`` for every part, yielded as each part finishes
        (any order on processes and Dask; in order when serial).  Pending work is cancelled
        if the caller stops early or an error is raised."""
        if self.backend == "serial":
            state = self.local
            for part in parts:
                yield [fn(state, item) for item in part]
            return
        if self.backend == "processes":
            pending = {self._pool.submit(_chunk_task, fn, list(p)) for p in parts}
            try:
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in done:
                        yield fut.result()
            finally:
                for fut in pending:
                    fut.cancel()
            return
        from distributed import as_completed

        futures = [self._client.submit(_dask_chunk, self.factory, fn, self._remote, list(p), pure=False)
                   for p in parts]
        try:
            for fut in as_completed(futures):
                yield fut.result()
        except BaseException:
            self._client.cancel(futures)
            raise

    # ---------------------------------------------------------------- closing
    def close(self, cancel: bool = False) -> None:
        """Shut the pool down (``cancel``: drop what has not started), or close an own Dask client."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=cancel)
            self._pool = None
        if self._client is not None and self._own:
            self._client.close()
        self._client = None

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.close(cancel=exc_type is not None)
        return False


class Progress:
    """The progress of a run: a tqdm bar on stderr (``progress=True``), a callback
    ``progress(done, total)`` (a callable), or nothing (False/None).

    Use :meth:`update` with the number just finished and the total done so far, and
    :meth:`close` at the end (or use it as a context manager).
    """

    def __init__(self, progress, total: int, *, initial: int = 0, desc: str = "", unit: str = "it",
                 show: bool = True, dynamic_ncols: bool = True):
        self.total = int(total)
        self.callback = progress if callable(progress) and progress is not True else None
        self.bar = None
        if progress is True and show:
            try:
                from tqdm import tqdm

                kwargs = {"dynamic_ncols": True} if dynamic_ncols else {}
                self.bar = tqdm(total=total, initial=initial, desc=desc, unit=unit, file=sys.stderr, **kwargs)
            except ImportError:  # pragma: no cover - tqdm is a dependency
                self.bar = None

    def update(self, n: int, done: int) -> None:
        """``n`` more finished, ``done`` finished in all."""
        if self.bar is not None:
            self.bar.update(n)
        elif self.callback is not None:
            self.callback(done, self.total)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
