"""The live view in a real browser (Debian's Chromium driven by Playwright): drag, type, save, the band.

Skipped, with the reason, where Playwright or Chromium is not installed (``.ci/run`` installs both).
"""

from __future__ import annotations

import shutil

import pytest

import crashsim
from crashsim.live.view import result_payload

playwright = pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (the test extra)")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no Chromium on this machine (Debian: apt-get install "
                                                         "chromium); .ci/run installs it")


@pytest.fixture(scope="module")
def browser():
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"])
        yield b
        b.close()


@pytest.fixture
def served(scene_copy):
    from crashsim.live.server import LiveServer

    srv = LiveServer(scene_copy, band_samples=32, workers=2)
    srv.start()
    yield srv, scene_copy
    srv.stop()


def _settled(page, timeout=60000):
    """Every change sent answered, and a result drawn after it (or the change refused)."""
    page.wait_for_function("window.__live.results > 0 && !window.__live.busy "
                           "&& (window.__live.lastDrawn >= window.__live.lastSent || window.__live.invalid > 0)",
                           timeout=timeout)


def _numbers(page) -> dict:
    return page.evaluate("""() => ({
        residuals: [...document.querySelectorAll('#evidence tr')].map(r => [r.cells[0].textContent, r.cells[2].textContent]),
        delta_v: [...document.querySelectorAll('#bodies td.delta-v')].map(c => c.textContent),
        car_path: document.querySelector('#layer-paths polyline[data-body=car]').getAttribute('points'),
        speed: document.querySelector('input[name="vehicles.B.speed"]').value,
        x: document.querySelector('input[name="vehicles.B.position[0]"]').value,
    })""")


def test_drag_type_save_and_run_give_the_pages_numbers(browser, served):
    srv, path = served
    before_text = path.read_text()
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(srv.url)
    _settled(page)
    first = _numbers(page)
    # drag the car at impact 15 px to the right (its front stays on the point of impact)
    box = page.locator('#layer-impactpose g[data-vehicle="B"] polygon').first.bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down()
    for k in range(1, 6):
        page.mouse.move(cx + 3 * k, cy)
    page.mouse.up()
    _settled(page)
    assert page.evaluate("window.__live.invalid") == 0
    dragged = _numbers(page)
    assert dragged["x"] != first["x"] and float(dragged["x"].split()[0]) > float(first["x"].split()[0])
    # type a speed in another unit than the file's
    speed = page.locator('input[name="vehicles.B.speed"]')
    speed.fill("40 mph")
    speed.press("Enter")
    page.wait_for_function("document.querySelector('input[name=\"vehicles.B.speed\"]').value === '17.8816 m/s'")
    _settled(page)
    now = _numbers(page)
    assert now["car_path"] != first["car_path"]
    assert now["delta_v"] != first["delta_v"]
    assert [r[0] for r in now["residuals"]] != [r[0] for r in first["residuals"]]  # a verdict turned
    # save: the comments stay, and crashsim run of the file gives the page's numbers
    page.click("#save")
    page.wait_for_function("document.getElementById('banner').textContent.startsWith('saved')")
    after_text = path.read_text()
    comments = [ln for ln in before_text.splitlines() if ln.lstrip().startswith("#")]
    assert all(ln in after_text.splitlines() for ln in comments)
    assert 'speed = "17.8816 m/s"' in after_text
    run = result_payload(crashsim.run(path), srv.session)
    assert [[("PASS" if c["passed"] else "FAIL"), c["residual"]] for c in run["evidence"]] == now["residuals"]
    assert [b["delta_v"] for b in run["bodies"]] == now["delta_v"]
    # the band of the saved state: drawn, with its share
    page.wait_for_function("window.__live.lastBand && document.querySelectorAll('#layer-band polyline').length > 0 "
                           "&& document.getElementById('band-info').textContent.includes('of 32 samples')",
                           timeout=120000)
    # a file edited on disk meanwhile: save refuses, the edit survives
    path.write_text(after_text + "\n# edited by someone else\n")
    page.locator('input[name="vehicles.B.speed"]').fill("41 mph")
    page.locator('input[name="vehicles.B.speed"]').press("Enter")
    _settled(page)
    page.click("#save")
    page.wait_for_function("document.getElementById('banner').textContent.includes('changed on disk')")
    assert path.read_text().endswith("# edited by someone else\n")
    assert page.locator("#banner button", has_text="Reload").count() == 1
    assert not errors


def test_an_invalid_value_shows_the_error_and_keeps_the_last_result(browser, served):
    srv, _ = served
    page = browser.new_page()
    page.goto(srv.url)
    _settled(page)
    before = _numbers(page)
    e = page.locator('input[name="impact.restitution"]')
    e.fill("1.5")
    e.press("Enter")
    page.wait_for_function("!document.getElementById('error').hidden")
    assert "impact.restitution" in page.inner_text("#error") and "allowed [0" in page.inner_text("#error")
    assert _numbers(page)["car_path"] == before["car_path"]
    assert page.locator('input[name="impact.restitution"]').input_value() == "0.05"
    # undo / redo of a change
    s = page.locator('input[name="vehicles.A.speed"]')
    s.focus()
    s.fill("12 m/s")
    s.press("Enter")
    page.wait_for_function("document.querySelector('input[name=\"vehicles.A.speed\"]').value === '12 m/s'")
    _settled(page)
    page.click("#undo")
    page.wait_for_function("document.querySelector('input[name=\"vehicles.A.speed\"]').value === '13.41 m/s'")
    page.click("#redo")
    page.wait_for_function("document.querySelector('input[name=\"vehicles.A.speed\"]').value === '12 m/s'")
