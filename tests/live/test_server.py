"""The live server's safety: the token, the Host and Origin checks, hostile messages, coalescing."""

from __future__ import annotations

import asyncio
import json

import pytest



def _run(coro):
    return asyncio.new_event_loop().run_until_complete(coro)


async def _get(srv, path, headers=None, token=True):
    import aiohttp

    q = f"?token={srv.token}" if token else ""
    async with aiohttp.ClientSession() as s:
        async with s.get(f"http://127.0.0.1:{srv.port}{path}{q}", headers=headers or {}) as r:
            return r.status, await r.read()


def test_the_page_needs_the_token(live_server):
    assert _run(_get(live_server, "/"))[0] == 200
    assert _run(_get(live_server, "/static/live.js"))[0] == 200
    status, body = _run(_get(live_server, "/", token=False))
    assert status == 403 and b"token" in body
    assert _run(_get(live_server, "/static/live.js", token=False))[0] == 403
    wrong = _run(_get(live_server, f"/?token={live_server.token[:-1]}x", token=False))
    assert wrong[0] == 403


def test_a_foreign_host_or_origin_is_refused(live_server):
    assert _run(_get(live_server, "/", headers={"Host": f"evil.example:{live_server.port}"}))[0] == 403  # DNS rebinding
    assert _run(_get(live_server, "/", headers={"Host": f"localhost:{live_server.port}"}))[0] == 200
    assert _run(_get(live_server, "/", headers={"Origin": "http://evil.example"}))[0] == 403


def test_no_file_but_the_pages_own_is_served(live_server):
    for path in ("/static/../session.py", "/static/live_server.py", "/static/%2e%2e%2fsession.py", "/scene.toml"):
        assert _run(_get(live_server, path))[0] in (403, 404)


async def _ws_session(srv, origin, messages, wait_for=None):
    import aiohttp

    got = []
    async with aiohttp.ClientSession() as s:
        async with s.ws_connect(f"ws://127.0.0.1:{srv.port}/ws?token={srv.token}",
                                headers={} if origin is None else {"Origin": origin}) as ws:
            for m in messages:
                await (ws.send_str(m) if isinstance(m, str) else ws.send_bytes(m))
            while True:
                msg = await asyncio.wait_for(ws.receive(), 60)
                if msg.type != aiohttp.WSMsgType.TEXT:
                    break
                got.append(json.loads(msg.data))
                if wait_for(got):
                    break
    return got


def test_the_websocket_needs_this_servers_origin(live_server):
    import aiohttp

    for origin in (None, "http://evil.example", f"http://127.0.0.1:{live_server.port + 1}"):
        with pytest.raises(aiohttp.WSServerHandshakeError) as e:
            _run(_ws_session(live_server, origin, [], lambda got: True))
        assert e.value.status == 403


def test_malformed_messages_are_answered_and_the_server_goes_on(live_server):
    origin = f"http://127.0.0.1:{live_server.port}"
    bad = ["not json", "[]", "3", "null", '{"type": 5}', '{"type": "exec", "code": "import os"}',
           '{"type": "set"}', '{"type": "set", "seq": "1", "values": {}}', '{"type": "set", "seq": 1, "values": []}',
           '{"type": "set", "seq": 1, "values": {"x": [1]}}', '{"type": "save_as", "name": 3}',
           '{"type": "set", "seq": true, "values": {}}', "{" * 5000, b"\x00\x01"]
    msgs = [bad[i % len(bad)] for i in range(200)]
    n_before = live_server.stats["errors"]
    got = _run(_ws_session(live_server, origin, msgs, lambda got: sum(m["type"] == "error" for m in got) >= 200))
    errors = [m for m in got if m["type"] == "error"]
    assert len(errors) == 200 and live_server.stats["errors"] - n_before == 200
    assert all(isinstance(m["error"], str) and m["error"] for m in errors)
    # still serving: a valid change, and an unknown input, answered
    got = _run(_ws_session(live_server, origin, ['{"type": "set", "seq": 7, "values": {"vehicles.B.speed": "31 mph"}}',
                                            '{"type": "set", "seq": 8, "values": {"vehicles.Z.speed": "31 mph"}}'],
                           lambda got: any(m.get("seq") == 8 for m in got)))
    kinds = {m.get("seq"): m["type"] for m in got if m.get("seq") in (7, 8)}
    assert kinds.get(8) == "invalid" and "not an input of this view" in next(m for m in got if m.get("seq") == 8)["error"]
    assert _run(_get(live_server, "/"))[0] == 200


def test_changes_sent_at_once_are_coalesced(live_server):
    origin = f"http://127.0.0.1:{live_server.port}"
    msgs = [json.dumps({"type": "set", "seq": 100 + i, "values": {"vehicles.B.speed": f"{30 + i * 0.01:.2f} mph"}})
            for i in range(100)]
    computed = live_server.stats["computed"]
    got = _run(_ws_session(live_server, origin, msgs, lambda got: any(m.get("seq") == 199 for m in got)))
    answered = [m["seq"] for m in got if m["type"] in ("result", "invalid") and m.get("seq", 0) >= 100]
    assert answered[-1] == 199  # the last change is the last answered
    assert answered == sorted(answered)
    assert live_server.stats["computed"] - computed < 100  # not one recompute per change: never a backlog
    last = next(m for m in got if m.get("seq") == 199)
    assert last["values"]["vehicles.B.speed"] == "13.8538 m/s"  # 30.99 mph in the file's unit


def test_export_gives_the_figure_and_the_report_only_of_a_saved_state(live_server):
    import aiohttp

    async def get(fmt):
        async with aiohttp.ClientSession() as s:
            async with s.get(f"http://127.0.0.1:{live_server.port}/export?format={fmt}&token={live_server.token}") as r:
                return r.status, r.headers.get("Content-Disposition", ""), await r.read()

    origin = f"http://127.0.0.1:{live_server.port}"
    _run(_ws_session(live_server, origin, ['{"type": "set", "seq": 300, "values": {"vehicles.B.speed": "13.41 m/s"}}'],
                     lambda got: any(m.get("seq") == 300 for m in got)))
    status, disposition, svg = _run(get("svg"))
    assert status == 200 and svg.lstrip().startswith(b"<?xml") and b"<svg" in svg and "attachment" in disposition
    status, _, png = _run(get("png"))
    assert status == 200 and png.startswith(b"\x89PNG")
    assert _run(get("exe"))[0] == 400
    status, _, html = _run(get("html"))  # the file's own values: the report names the file
    assert status == 200 and b"<html" in html.lower() and live_server.session.path.name.encode() in html
    _run(_ws_session(live_server, origin, ['{"type": "set", "seq": 301, "values": {"vehicles.B.speed": "31 mph"}}'],
                     lambda got: any(m.get("seq") == 301 for m in got)))
    status, _, text = _run(get("html"))
    assert status == 409 and b"save the view's changes first" in text
    _run(_ws_session(live_server, origin, ['{"type": "set", "seq": 302, "values": {"vehicles.B.speed": "13.41 m/s"}}'],
                     lambda got: any(m.get("seq") == 302 for m in got)))


def test_saved_says_what_it_wrote_and_what_still_differs(live_server):
    """A save as a new file: its reply names the values written (the one changed input) and what still
    differs from the open file (the same: the open file is not the one written)."""
    origin = f"http://127.0.0.1:{live_server.port}"
    _run(_ws_session(live_server, origin, ['{"type": "set", "seq": 400, "values": {"vehicles.B.speed": "31 mph"}}'],
                     lambda got: any(m.get("seq") == 400 for m in got)))
    got = _run(_ws_session(live_server, origin, ['{"type": "save_as", "name": "saved-copy.toml"}'],
                           lambda got: any(m["type"] in ("saved", "save_refused") for m in got)))
    (saved,) = [m for m in got if m["type"] == "saved"]
    assert saved["path"].endswith("saved-copy.toml")
    assert saved["values"] == {"vehicles.B.speed": "13.8582 m/s"} == saved["changed"]
    copy = (live_server.session.path.parent / "saved-copy.toml").read_text(encoding="utf-8").splitlines()
    opened = live_server.session.path.read_text(encoding="utf-8").splitlines()
    assert len(copy) == len(opened)  # nothing added: no default the file leaves out
    assert [b for a, b in zip(opened, copy) if a != b] == ['speed = "13.8582 m/s"']
    _run(_ws_session(live_server, origin, ['{"type": "set", "seq": 401, "values": {"vehicles.B.speed": "13.41 m/s"}}'],
                     lambda got: any(m.get("seq") == 401 for m in got)))


@pytest.mark.slow
def test_fit_from_here_answers_with_the_fit(live_server):
    origin = f"http://127.0.0.1:{live_server.port}"
    got = _run(_ws_session(live_server, origin, ['{"type": "fit"}'], lambda got: any(m["type"] == "fit" for m in got)))
    fit = next(m for m in got if m["type"] == "fit")
    assert fit["ok"], fit
    paths = [u["path"] for u in fit["unknowns"]]
    assert paths == ["vehicles.A.speed", "vehicles.B.speed", "impact.restitution", "runout.road_friction"]
    speed_b = next(u for u in fit["unknowns"] if u["path"] == "vehicles.B.speed")
    lo, hi = (float(x.split()[0]) for x in speed_b["interval"])
    assert lo <= float(speed_b["value"].split()[0]) <= hi and 0 < fit["n_agree"] <= fit["starts"]
