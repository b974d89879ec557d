"""The live view's local web server (aiohttp: one package for HTTP and websockets, no ASGI stack).

Safety, as a notebook server keeps it:

- bound to 127.0.0.1 only;
- a random token (``secrets.token_urlsafe``) in the URL, required on every request and on the
  websocket (given as ``?token=``, or by the cookie the first page load sets);
- the ``Host`` header must name this server (127.0.0.1 or localhost and its port: no DNS
  rebinding), and an ``Origin`` header, required on the websocket, must be this server's (no
  cross-site use);
- no file is served but the page's own three files and the scene's survey underlay; the only file
  written is the opened scene (save) or a new file beside it (save as); no code is run from a
  message;
- a message that is not what the protocol allows gets an error reply; the server goes on.

Recompute: the page sends the whole set of values it holds with a sequence number. A change that
arrives while the scene is computing replaces the one waiting (only the latest runs: never a
backlog). The result carries the sequence number it answers. Once the changes come to rest the
Monte Carlo band (``[uncertainty]``) runs on the worker processes and is sent if no change came
meanwhile.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import hmac
import json
import multiprocessing
import os
import secrets
import signal
import tempfile
import threading
import time
from importlib import resources
from pathlib import Path

from ..casereport import survey_files, write_case_report
from ..errors import CrashsimError, ScenarioError
from ..plotting import save_scene_figures
from ..reconstruct.fit import fit_scene
from ..scenario import presets
from ..units import format_value
from .band import band_worker_init, run_band_chunk
from .session import LiveSession
from .view import band_payload

__all__ = ["LiveServer", "open_live", "STATIC_FILES", "BAND_SAMPLES", "BAND_DELAY"]

#: The only files the server serves from the package (name -> content type).
STATIC_FILES = {"index.html": "text/html", "live.js": "text/javascript", "live.css": "text/css"}
#: Samples of the Monte Carlo band.
BAND_SAMPLES = 32
#: Seconds without a change after which the band runs.
BAND_DELAY = 0.25
#: The largest message the websocket accepts (bytes).
MAX_MESSAGE = 1 << 20
_COOKIE = "crashsim_live_token"


def _static(name: str) -> bytes:
    return resources.files("crashsim.live").joinpath("static", name).read_bytes()


class LiveServer:
    """A live view of one scene file, served on 127.0.0.1.

    Parameters
    ----------
    path : str or Path
        The scenario file.
    port : int
        0: a free port.
    band_samples : int
        Samples of the Monte Carlo band (with ``[uncertainty]``; 0: no band).
    workers : int
        Worker processes of the band.
    engine : str
        Run-out engine of the view.

    Attributes
    ----------
    url : str
        The page's address with its token (after :meth:`start`).
    """

    def __init__(self, path, *, port: int = 0, band_samples: int = BAND_SAMPLES, workers: int = 2,
                 engine: str = "compiled", token: str | None = None):
        self.session = LiveSession(path, engine=engine)  # a bad file raises here, before any serving
        self.token = token or secrets.token_urlsafe(32)
        self.port = int(port)
        self.band_samples = int(band_samples) if self.session.band_inputs() is not None else 0
        self.workers = max(1, int(workers))
        self._compute = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="crashsim-live")
        self._fitter = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="crashsim-fit")
        self._pool = None
        self._clients: set = set()
        self._pending = None  # (seq, values) of the latest change not yet computed
        self._wake = None
        self._generation = 0  # of the last computed result: a band of an older one is dropped
        self._last = None  # the last result message sent
        self._last_band = None  # and the last band
        self._band_task = None
        self._thread = None
        self._loop = None
        self._runner = None
        self.url = None
        self.stats = {"messages": 0, "errors": 0, "computed": 0, "coalesced": 0, "bands": 0}
        # the first result, and the band's workers, made here in the calling thread before the
        # server's threads exist: the workers are forked (where the platform can) with the kernels
        # the first result loaded, and a fork never copies a process that runs other threads
        self._first = self.session.apply({})
        if self.band_samples:
            self._start_band_pool()

    # -- the app ---------------------------------------------------------------------------------
    def _allowed_hosts(self) -> set:
        return {f"127.0.0.1:{self.port}", f"localhost:{self.port}"}

    def _check(self, request, websocket: bool = False):
        """None if the request may be served, else the refusal (a response)."""
        from aiohttp import web

        if request.host not in self._allowed_hosts():
            return web.Response(status=403, text="refused: this server answers only to its own address (Host)")
        origin = request.headers.get("Origin")
        if (origin is not None or websocket) and origin not in {f"http://{h}" for h in self._allowed_hosts()}:
            return web.Response(status=403, text="refused: a page of another origin may not use this server")
        token = request.query.get("token") or request.cookies.get(_COOKIE) or ""
        if not hmac.compare_digest(token.encode(), self.token.encode()):
            return web.Response(status=403, text="refused: the token of this server is required (see the URL "
                                "crashsim live printed)")
        return None

    def app(self):
        from aiohttp import web

        @web.middleware
        async def guard(request, handler):
            refused = self._check(request, websocket=request.path == "/ws")
            if refused is not None:
                return refused
            return await handler(request)

        app = web.Application(middlewares=[guard], client_max_size=MAX_MESSAGE)
        app.router.add_get("/", self._index)
        app.router.add_get("/static/{name}", self._file)
        app.router.add_get("/underlay.png", self._underlay)
        app.router.add_get("/export", self._export)
        app.router.add_get("/ws", self._ws)
        app.on_shutdown.append(self._on_shutdown)
        return app

    async def _index(self, request):
        from aiohttp import web

        r = web.Response(body=_static("index.html"), content_type="text/html",
                         headers={"Cache-Control": "no-store", "X-Frame-Options": "SAMEORIGIN",
                                  "Referrer-Policy": "no-referrer"})
        r.set_cookie(_COOKIE, self.token, httponly=True, samesite="Strict")
        return r

    async def _file(self, request):
        from aiohttp import web

        name = request.match_info["name"]
        if name not in STATIC_FILES:
            return web.Response(status=404, text="not found")
        return web.Response(body=_static(name), content_type=STATIC_FILES[name], headers={"Cache-Control": "no-store"})

    async def _underlay(self, request):
        from aiohttp import web

        png = await asyncio.get_running_loop().run_in_executor(self._compute, self.session.underlay_png)
        if png is None:
            return web.Response(status=404, text="this scene has no survey underlay")
        return web.Response(body=png, content_type="image/png")

    async def _export(self, request):
        """The current figure (``?format=png|svg|pdf``) or the case report (``format=html``), as a download."""
        from aiohttp import web

        fmt = request.query.get("format", "png")
        if fmt not in ("png", "svg", "pdf", "html"):
            return web.Response(status=400, text=f"format = {fmt!r}: allowed png, svg, pdf, html")
        try:
            body = await asyncio.get_running_loop().run_in_executor(self._compute, self._export_bytes, fmt)
        except CrashsimError as exc:
            return web.Response(status=409, text=str(exc))
        name = f"{self.session.path.stem}-live.{fmt}"
        types = {"png": "image/png", "svg": "image/svg+xml", "pdf": "application/pdf", "html": "text/html"}
        return web.Response(body=body, content_type=types[fmt],
                            headers={"Content-Disposition": f'attachment; filename="{name}"'})

    def _export_bytes(self, fmt: str) -> bytes:
        s = self.session
        if s.result is None:
            raise ScenarioError("no result to export yet", field="export", file=s.file)
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / f"scene.{fmt}"
            if fmt == "html":
                if s.changed() or s.changed_on_disk():
                    raise ScenarioError("a case report names the file it was made from: save the view's changes "
                                        "first", field="export", file=s.file)
                write_case_report(s.result, out, input_files=[s.file] + survey_files(s.file), presets=presets(),
                                  command=f"crashsim live {s.path.name} (exported)")
            else:
                save_scene_figures(s.result, out)
            return out.read_bytes()

    # -- the websocket ---------------------------------------------------------------------------
    async def _send(self, ws, msg: dict) -> None:
        try:
            await ws.send_str(json.dumps(msg, allow_nan=False, default=float))
        except (ConnectionError, RuntimeError):
            pass

    async def _broadcast(self, msg: dict) -> None:
        for ws in list(self._clients):
            await self._send(ws, msg)

    async def _ws(self, request):
        from aiohttp import WSMsgType, web

        ws = web.WebSocketResponse(max_msg_size=MAX_MESSAGE, heartbeat=30)
        await ws.prepare(request)
        self._clients.add(ws)
        try:
            await self._send(ws, {"type": "static", **self.session.static()})
            if self._last is not None:
                await self._send(ws, self._last)
            if self._last_band is not None and self._last is not None \
                    and self._last_band["generation"] == self._last["generation"]:
                await self._send(ws, self._last_band)
            async for msg in ws:
                if msg.type == WSMsgType.TEXT:
                    await self._on_message(ws, msg.data)
                elif msg.type == WSMsgType.BINARY:
                    self.stats["errors"] += 1
                    await self._send(ws, {"type": "error", "error": "binary messages are not part of the protocol"})
        finally:
            self._clients.discard(ws)
        return ws

    async def _on_message(self, ws, text: str) -> None:
        self.stats["messages"] += 1
        try:
            msg = json.loads(text)
        except (ValueError, RecursionError):
            self.stats["errors"] += 1
            return await self._send(ws, {"type": "error", "error": "not a JSON message"})
        if not isinstance(msg, dict) or not isinstance(msg.get("type"), str):
            self.stats["errors"] += 1
            return await self._send(ws, {"type": "error", "error": "a message is a JSON object with a \"type\""})
        kind = msg["type"]
        handler = {"set": self._on_set, "save": self._on_save, "save_as": self._on_save, "reload": self._on_reload,
                   "fit": self._on_fit, "ping": self._on_ping}.get(kind)
        if handler is None:
            self.stats["errors"] += 1
            return await self._send(ws, {"type": "error", "error": f"unknown message type {kind[:40]!r}; allowed: "
                                         "set, save, save_as, reload, fit, ping"})
        try:
            await handler(ws, msg)
        except (TypeError, ValueError, KeyError, AttributeError) as exc:
            self.stats["errors"] += 1
            await self._send(ws, {"type": "error", "error": f"malformed {kind!r} message: {exc}"[:300]})

    async def _on_ping(self, ws, msg):
        await self._send(ws, {"type": "pong", "stats": self.stats})

    async def _on_set(self, ws, msg):
        seq, values = msg.get("seq"), msg.get("values")
        if not isinstance(seq, int) or isinstance(seq, bool) or not isinstance(values, dict) or len(values) > 200:
            raise ValueError('a "set" message is {"type": "set", "seq": integer, "values": {path: value}}')
        if not all(isinstance(k, str) and isinstance(v, (str, int, float)) and not isinstance(v, bool)
                   for k, v in values.items()):
            raise ValueError("each value is a number or a text with its unit, by its path")
        if self._pending is not None:
            self.stats["coalesced"] += 1
        self._pending = (seq, values)
        self._wake.set()

    async def _compute_loop(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            await self._wake.wait()
            self._wake.clear()
            if self._pending is None:
                continue
            seq, values = self._pending
            self._pending = None
            out = await loop.run_in_executor(self._compute, self.session.apply, values)
            self.stats["computed"] += 1
            self._generation += 1
            msg = {"type": "result" if out["ok"] else "invalid", "seq": seq, "generation": self._generation,
                   "changed": self.session.changed(), **out}
            if out["ok"]:
                self._last = msg
            await self._broadcast(msg)
            if out["ok"] and self.band_samples:
                if self._band_task is not None:
                    self._band_task.cancel()
                self._band_task = asyncio.ensure_future(self._band_after_rest(self._generation))

    async def _band_after_rest(self, generation: int) -> None:
        await asyncio.sleep(BAND_DELAY)
        if generation != self._generation or self._pending is not None:
            return
        loop = asyncio.get_running_loop()
        t0 = time.perf_counter()
        payload, rows = await loop.run_in_executor(self._compute, self.session.band_task, self.band_samples)
        pool = self._band_pool()
        k = self.workers * 2
        chunks = [rows[i::k] for i in range(k)]
        futures = [loop.run_in_executor(pool, run_band_chunk, payload, c) for c in chunks if c]
        parts = await asyncio.gather(*futures)
        rows_out = [None] * len(rows)
        for i, part in enumerate(parts):
            rows_out[i::k] = part
        if generation != self._generation:
            return  # a newer change came meanwhile: its own band follows
        self.stats["bands"] += 1
        msg = {"type": "band", "generation": generation, "seconds": time.perf_counter() - t0,
               **band_payload(rows_out, len(rows), self.session.system)}
        self._last_band = msg
        await self._broadcast(msg)

    def _start_band_pool(self) -> None:
        ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
        self._pool = concurrent.futures.ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=band_worker_init,
                                                            initargs=(os.getpid(),))
        payload, rows = self.session.band_task(1)
        for f in [self._pool.submit(run_band_chunk, payload, rows) for _ in range(self.workers)]:
            f.result()  # every worker started, its runner built

    def _band_pool(self):
        if self._pool is None:  # (closed: a server started again)
            self._start_band_pool()
        return self._pool

    async def _on_save(self, ws, msg):
        name = msg.get("name") if msg["type"] == "save_as" else None
        if msg["type"] == "save_as" and not isinstance(name, str):
            raise ValueError('a "save_as" message is {"type": "save_as", "name": "new-file.toml"}')
        loop = asyncio.get_running_loop()
        try:
            # "values": what the save wrote, taken before it; "changed": what still differs from the file
            # the view has open (nothing after saving into it; a save as a new file leaves it as it was)
            wrote, written = await loop.run_in_executor(
                self._compute, lambda: (self.session.changed(), self.session.save(name)))
        except ScenarioError as exc:
            return await self._send(ws, {"type": "save_refused", "error": str(exc),
                                         "changed_on_disk": self.session.changed_on_disk()})
        except OSError as exc:  # the folder or the file not writable: nothing written, the view goes on
            where = f" {exc.filename!r}" if exc.filename else ""
            return await self._send(ws, {"type": "save_refused", "error": f"could not write{where}: "
                                         f"{exc.strerror or exc}", "changed_on_disk": False})
        await self._broadcast({"type": "saved", "path": written, "values": wrote, "changed": self.session.changed()})

    async def _on_reload(self, ws, msg):
        loop = asyncio.get_running_loop()
        try:
            out = await loop.run_in_executor(self._compute, self.session.reload)
        except CrashsimError as exc:
            return await self._send(ws, {"type": "invalid", "error": str(exc)})
        self._generation += 1
        await self._broadcast({"type": "static", **self.session.static()})
        msg = {"type": "result" if out["ok"] else "invalid", "seq": -1, "generation": self._generation,
               "changed": self.session.changed(), **out}
        if out["ok"]:
            self._last = msg
        await self._broadcast(msg)

    async def _on_fit(self, ws, msg):
        if not self.session.has_fit:
            return await self._send(ws, {"type": "fit", "ok": False, "error": "this file has no [fit] unknowns"})
        loop = asyncio.get_running_loop()
        data = await loop.run_in_executor(self._compute, self.session.fit_inputs)
        await self._send(ws, {"type": "fit_started"})
        out = await loop.run_in_executor(self._fitter, _fit, data, self.session.file, self.workers)
        await self._send(ws, {"type": "fit", **out})

    # -- running ---------------------------------------------------------------------------------
    async def _on_shutdown(self, app):
        for ws in list(self._clients):
            await ws.close()

    async def _serve(self, started: threading.Event | None = None) -> None:
        from aiohttp import web

        self._wake = asyncio.Event()
        runner = web.AppRunner(self.app(), access_log=None, handle_signals=False)
        await runner.setup()
        site = web.TCPSite(runner, "127.0.0.1", self.port)
        await site.start()
        if self.port == 0:
            self.port = runner.addresses[0][1]
        self._runner = runner
        self.url = f"http://127.0.0.1:{self.port}/?token={self.token}"
        first, self._first = self._first or self.session.apply({}), None
        self._generation += 1
        self._last = {"type": "result" if first["ok"] else "invalid", "seq": 0, "generation": self._generation,
                      "changed": {}, **first}
        compute = asyncio.ensure_future(self._compute_loop())
        if self.band_samples:
            self._band_task = asyncio.ensure_future(self._band_after_rest(self._generation))
        if started is not None:
            started.set()
        try:
            await asyncio.Event().wait()  # until cancelled
        finally:
            compute.cancel()
            await runner.cleanup()

    def start(self) -> str:
        """Serve in a background thread (a notebook, a test); returns the URL once it answers."""
        started = threading.Event()

        def main():
            self._loop = asyncio.new_event_loop()
            self._main = self._loop.create_task(self._serve(started))
            try:
                self._loop.run_until_complete(self._main)
            except asyncio.CancelledError:
                pass
            finally:
                self._loop.close()

        self._thread = threading.Thread(target=main, name="crashsim-live-server", daemon=True)
        self._thread.start()
        if not started.wait(120):
            raise RuntimeError("the live server did not start within 120 s")
        return self.url

    def run(self, on_ready=None) -> None:
        """Serve in this thread until interrupted (the command line); ``on_ready(url)`` once it answers."""
        started = threading.Event()

        async def main():
            task = asyncio.ensure_future(self._serve(started))
            try:  # SIGTERM (a service manager, kill) stops the server as Ctrl+C does: its workers with it
                asyncio.get_running_loop().add_signal_handler(signal.SIGTERM, task.cancel)
            except (NotImplementedError, RuntimeError):  # no signals here (Windows, not the main thread)
                pass
            while not started.is_set() and not task.done():
                await asyncio.sleep(0.05)
            if on_ready is not None and started.is_set():
                on_ready(self.url)
            await task

        try:
            asyncio.run(main())
        except (KeyboardInterrupt, asyncio.CancelledError):
            pass
        finally:
            self.close()

    def stop(self) -> None:
        """Stop a server started with :meth:`start`."""
        if self._loop is not None and self._thread is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._main.cancel)
            self._thread.join(30)
        self.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None
        self._compute.shutdown(wait=False, cancel_futures=True)
        self._fitter.shutdown(wait=False, cancel_futures=True)

    # -- a notebook ------------------------------------------------------------------------------
    def _repr_html_(self) -> str:
        return (f'<iframe src="{self.url}" width="100%" height="720" style="border:1px solid #ccc"></iframe>'
                if self.url else "<i>live view not started</i>")


def _fit(data: dict, file: str, workers: int) -> dict:
    """Run the fit of ``data`` (the view's values as the starts' first); its result as the page shows it."""
    try:
        r = fit_scene(data, None, file=file, workers=workers, progress=False)
    except CrashsimError as exc:
        return {"ok": False, "error": str(exc)}
    system = data.get("scenario", {}).get("units", "SI")
    rows = []
    for u, x, lo_hi in zip(r.unknowns, r.x, r.interval):
        kind = u.kind
        rows.append({"path": u.path, "value": format_value(x, kind, system, digits=5),
                     "interval": [format_value(v, kind, system, digits=4) for v in lo_hi], "si": float(x)})
    return {"ok": True, "success": bool(r.success), "unknowns": rows, "n_agree": int(r.n_agree),
            "starts": len(r.starts), "warnings": list(r.warnings)}


def open_live(path, **kwargs) -> LiveServer:
    """The live view of a scene file, served in the background (a notebook shows it inline).

    >>> view = open_live("scenarios/scenes/intersection_car_trailer_wheels.toml")  # doctest: +SKIP
    >>> view            # in a notebook: the page in an iframe                      # doctest: +SKIP
    >>> view.stop()                                                                # doctest: +SKIP
    """
    server = LiveServer(path, **kwargs)
    server.start()
    return server
