"""Fixtures of the live view's tests: a copy of a shipped scene (the tests write into it) and a server."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIT_SCENE = ROOT / "scenarios" / "fit" / "intersection_fit.toml"

pytest.importorskip("aiohttp", reason="the live view's extra (pip install -e '.[live]') is not installed")
pytest.importorskip("tomlkit", reason="the live view's extra (pip install -e '.[live]') is not installed")


@pytest.fixture
def scene_copy(tmp_path) -> Path:
    out = tmp_path / "scene.toml"
    shutil.copy(FIT_SCENE, out)
    return out


@pytest.fixture(scope="module")
def live_server(tmp_path_factory):
    """A live server of a copy of the fit scene, without the band (its own tests start one with it)."""
    from crashsim.live.server import LiveServer

    f = tmp_path_factory.mktemp("live") / "scene.toml"
    shutil.copy(FIT_SCENE, f)
    srv = LiveServer(f, band_samples=0)
    srv.start()
    yield srv
    srv.stop()
