"""The case report (``crashsim report FILE -o case.html``): one self-contained HTML file with the inputs and
their comments, the impacts, the run-out, the evidence, the figures, the program version, the date and the
SHA-256 of every input file.

* the HTML is well formed (every element closed in order; the standard library's html.parser);
* no http(s) URL anywhere in it, every figure an embedded data URI;
* a real headless Chromium renders it to a PDF and a screenshot, with the sections and the figures present
  in the parsed page and no request made by the page (skipped, with the reason, where Chromium is absent).
"""

from __future__ import annotations

import datetime as dt
import hashlib
import html
import json
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from crashsim.casereport import made_from

from crashsim.casereport import FILE_COMMENT, input_rows, render_case_report, toml_comments
from crashsim.cli import main
from crashsim.reconstruct import run_scene
from crashsim.scenario import load_scenario, presets

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"
SECTIONS = ("summary", "input-files", "inputs", "impacts", "runout", "events", "energy", "evidence", "figures",
            "assumptions")
VOID = {"meta", "link", "img", "br", "hr", "col", "input", "source", "wbr", "area", "base", "embed", "track"}


class _WellFormed(HTMLParser):
    """Every non-void element closed, in order; records ids, img sources and the text."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.ids, self.imgs, self.text = [], [], [], [], []
        self.doctype = False

    def handle_decl(self, decl):
        self.doctype = self.doctype or decl.lower() == "doctype html"

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.append(a["id"])
        if tag == "img":
            self.imgs.append(a.get("src", ""))
        if tag not in VOID:
            self.stack.append((tag, self.getpos()))

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.stack.pop()

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1][0] != tag:
            self.errors.append(f"</{tag}> at {self.getpos()} closes {self.stack[-1] if self.stack else 'nothing'}")
            return
        self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)


def _check(text: str) -> _WellFormed:
    p = _WellFormed()
    p.feed(text)
    p.close()
    assert p.doctype, "no <!DOCTYPE html>"
    assert not p.errors, p.errors[:5]
    assert not p.stack, f"unclosed elements: {p.stack[:5]}"
    assert len(set(p.ids)) == len(p.ids), "repeated ids"
    return p


def test_the_checker_finds_a_broken_page():
    p = _WellFormed()
    p.feed("<!DOCTYPE html><html><body><table><tr><td>x</tr></table></body></html>")
    assert p.errors


def test_comments_by_key_path():
    text = """# the scene
# of a test

[scenario]
title = "t"  # trailing
# above the key
units = "SI"

[[vehicles.A.bodies]]
name = "x"   # first body
axles = [
  { x = "1 m" },  # not a key
]
[[vehicles.A.bodies]]
# the second body
mass = "10 kg"
[impact]  # a table note
speed = "3 m/s # not a comment"
"""
    c = toml_comments(text)
    assert c[FILE_COMMENT] == "the scene of a test"
    assert c["scenario.title"] == "trailing"
    assert c["scenario.units"] == "above the key"
    assert c["vehicles.A.bodies[0].name"] == "first body"
    assert c["vehicles.A.bodies[1].mass"] == "the second body"
    assert c["impact"] == "a table note"
    assert "impact.speed" not in c and not any("not a key" in v for v in c.values())


def test_every_value_of_the_file_is_a_row_with_its_unit():
    text = SCENE.read_text(encoding="utf-8")
    import tomllib

    raw = tomllib.loads(text)
    sc = load_scenario(SCENE)
    rows = input_rows(raw, toml_comments(text), sc.data, presets())
    by_key = {r["key"]: r for r in rows}
    speed = by_key["vehicles.B.speed"]
    assert (speed["value"], speed["unit"], speed["si"]) == ('"13.41 m/s"', "m/s", "13.41")
    # values taken from a preset are listed, marked with it
    preset_rows = [r for r in rows if r["origin"].startswith("preset ")]
    assert any(r["key"].endswith(".yaw_inertia") and r["si"] == "48000" for r in preset_rows)
    # every leaf of the file is a row
    def leaves(node, path=""):
        if isinstance(node, dict):
            for k, v in node.items():
                yield from leaves(v, f"{path}.{k}" if path else k)
        elif isinstance(node, list) and node and all(isinstance(v, dict) for v in node):
            for i, v in enumerate(node):
                yield from leaves(v, f"{path}[{i}]")
        else:
            yield path
    assert set(leaves(raw)) <= set(by_key)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("case") / "case.html"
    fit = tmp_path_factory.getbasetemp() / "fit.json"
    fit.write_text(json.dumps({"success": True, "message": "converged", "chi2": 1.5, "dof": 3, "p_value": 0.68,
                               "confidence": 0.95, "n_agree": 4, "n_starts": 4, "warnings": [],
                               "unknowns": [{"path": "vehicles.car.speed", "name": "car speed", "kind": "speed",
                                             "value": 13.41, "stderr": 0.2, "interval": [13.0, 13.8]}],
                               "linearity": [{"step": {"vehicles.car.speed": s}, "predicted": 1.0, "actual": a,
                                              "linear": 0.5 <= a <= 2.0} for s, a in ((0.2, 1.1), (-0.2, 3.0))],
                               "linearity_factor": 2.0, "linearity_skipped": 1, "made_from": made_from("fit", SCENE)}))
    assert main(["report", str(SCENE), "-o", str(out), "--fit", str(fit), "--units", "US"]) == 0
    return out, fit


def test_the_report_is_well_formed_and_self_contained(report):
    out, fit = report
    text = out.read_text(encoding="utf-8")
    p = _check(text)
    for s in SECTIONS + ("fit",):
        assert s in p.ids, s
    assert not re.search(r"https?://", text), "an external URL in the page"
    assert not re.search(r"""(?:src|href)\s*=\s*["'](?!data:|#)""", text), "a link to another file"
    assert len(p.imgs) >= 3 and all(s.startswith("data:image/svg+xml;base64,") for s in p.imgs)
    body = html.unescape(" ".join(p.text))
    # the SHA-256 of every input file, the version, the date
    for f in (SCENE, fit):
        assert hashlib.sha256(f.read_bytes()).hexdigest() in body
    from crashsim import __version__

    assert f"crashsim {__version__}" in body
    assert dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d") in body
    # inputs with units and comments, impact, evidence verdicts, fit, validity notes
    assert '"13.41 m/s"' in body and "30 mph" in body  # as written, and in the report's units
    assert "PASS" in body and "Evidence" in body
    assert "car speed" in body and "29.08 mph to 30.87 mph" in body  # the fit interval (13.0, 13.8 m/s) in mph
    assert "1 of 2 points one standard error from the best pass (chi^2 within 2x of the linearised rise); 1 direction at a bound not probed" in body
    assert "instantaneous and planar" in body


def test_report_options_are_checked_before_work(tmp_path, capsys):
    assert main(["report", str(SCENE), "-o", str(tmp_path / "case.pdf")]) == 2
    assert "allowed: .html" in capsys.readouterr().err
    assert main(["report", str(SCENE), "-o", str(tmp_path / "c.html"), "--mc", str(tmp_path / "none.json")]) == 2
    assert "--mc" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2]")
    assert main(["report", str(SCENE), "-o", str(tmp_path / "c.html"), "--posterior", str(bad)]) == 2
    assert "not a JSON object" in capsys.readouterr().err


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium on this machine (Debian: apt-get install chromium); "
                                             ".ci/run installs it")
def test_chromium_renders_the_report(report, tmp_path):
    out, _ = report
    base = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={tmp_path / 'profile'}",
            "--host-resolver-rules=MAP * ~NOTFOUND"]
    url = out.resolve().as_uri()
    pdf, png, net = tmp_path / "case.pdf", tmp_path / "case.png", tmp_path / "net.json"
    subprocess.run(base + [f"--log-net-log={net}", f"--print-to-pdf={pdf}", "--no-pdf-header-footer", url],
                   check=True, capture_output=True, timeout=180)
    subprocess.run(base + [f"--screenshot={png}", "--window-size=1000,1400", url], check=True, capture_output=True,
                   timeout=180)
    dom = subprocess.run(base + ["--dump-dom", url], check=True, capture_output=True, text=True, timeout=180).stdout
    # the PDF: several pages
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF")
    assert len(re.findall(rb"/Type\s*/Page[^s]", data)) >= 3
    # the screenshot: a page with text on it, not blank
    from PIL import Image

    im = Image.open(png).convert("L")
    assert im.size == (1000, 1400)
    lo, hi = im.getextrema()
    assert hi - lo > 150
    # the page as the browser parsed it: every section and figure
    for s in SECTIONS:
        assert f'id="{s}"' in dom, s
    assert len(re.findall(r'<img src="data:image/svg\+xml;base64,', dom)) >= 3
    # the whole page as laid out at 1000 px: every section and figure drawn with a size, in order, and a
    # screenshot as high as the page whose content reaches its bottom (nothing after the first screen lost)
    layout = _layout(base, out, tmp_path)
    tops = [layout["sections"][s]["top"] for s in SECTIONS]
    assert all(layout["sections"][s]["height"] > 10 for s in SECTIONS), layout["sections"]
    assert tops == sorted(tops) and tops[-1] < layout["height"]
    assert len(layout["imgs"]) >= 3 and all(w > 100 and h > 100 for w, h in layout["imgs"]), layout["imgs"]
    height = layout["height"]
    assert height > 3 * 1400, "the report is several screens long"
    full = tmp_path / "full.png"
    subprocess.run(base + [f"--screenshot={full}", f"--window-size=1000,{height}", url], check=True,
                   capture_output=True, timeout=180)
    im = Image.open(full).convert("L")
    assert im.size == (1000, height)
    rows = np.flatnonzero((np.asarray(im) < 200).any(axis=1))  # rows with ink on them
    assert rows[0] < 200 and rows[-1] > height - 400, (rows[0], rows[-1], height)
    # ink spread over the whole page, no blank screen in it (a figure or a table failed to draw)
    gaps = np.diff(rows)
    assert gaps.max() < 700, int(gaps.max())
    # no request made by the page (the browser's own background requests have no origin)
    log = json.loads(net.read_text())
    types = {v: k for k, v in log["constants"]["logEventTypes"].items()}
    page = [e["params"]["url"] for e in log["events"]
            if types.get(e["type"]) == "URL_REQUEST_START_JOB" and "url" in e.get("params", {})
            and e["params"].get("initiator") != "not an origin"]
    assert not page, page


_PROBE = """<script>window.addEventListener("load", () => {
  const box = (e) => { const r = e.getBoundingClientRect(); return {top: r.top + window.scrollY, height: r.height}; };
  const sections = {};
  for (const e of document.querySelectorAll("[id]")) sections[e.id] = box(e);
  const imgs = [...document.images].map((i) => [i.complete ? i.naturalWidth : 0, box(i).height]);
  document.body.setAttribute("data-layout", JSON.stringify(
    {height: document.documentElement.scrollHeight, sections: sections, imgs: imgs}));
});</script>"""


def _layout(base: list, page: Path, tmp_path: Path) -> dict:
    """Where Chromium lays out each element with an id, the size of each image and the page's height
    [CSS px] at 1000 px wide: a copy of the page with a script that writes them into the DOM."""
    probe = tmp_path / "probe.html"
    probe.write_text(page.read_text(encoding="utf-8").replace("</body>", _PROBE + "</body>"), encoding="utf-8")
    dom = subprocess.run(base + ["--window-size=1000,1400", "--virtual-time-budget=5000", "--dump-dom",
                                 probe.resolve().as_uri()], check=True, capture_output=True, text=True,
                         timeout=180).stdout
    found = re.search(r'data-layout="([^"]*)"', dom)
    assert found, "the layout probe did not run"
    return json.loads(html.unescape(found[1]))


def test_render_without_figures_is_quick_and_names_every_input(tmp_path):
    scene = run_scene(load_scenario(SCENE))
    text = render_case_report(scene, input_files=[SCENE], figures=False,
                              now=dt.datetime(2026, 1, 2, 3, 4, tzinfo=dt.timezone.utc))
    p = _check(text)
    assert "figures" not in p.ids
    assert "2026-01-02 03:04 UTC" in text
    assert hashlib.sha256(SCENE.read_bytes()).hexdigest() in text


def test_monte_carlo_and_posterior_sections_in_the_users_units(tmp_path):
    """Shaped as ``crashsim mc --json`` and ``crashsim posterior --json`` write them (keys, percentile names)."""
    from crashsim.reconstruct.montecarlo import OUTPUT_KINDS

    scene = run_scene(load_scenario(SCENE))
    mc = {"n": 8, "n_done": 8, "n_failed": 0, "seed": 2026, "pass_share": 0.5,
          "percentiles": {"speed.A": {"p5": 13.4112, "p50": 13.4112, "p95": 13.4112, "mean": 13.4112, "std": 0.0},
                          "energy_loss.system": {"p5": 0.25, "p50": 0.5, "p95": 0.75, "mean": 0.5, "std": 0.1}}}
    post = {"success": True, "message": "ok", "warnings": ["chain short"],
            "diagnostics": {"samples": 100, "acceptance_mean": 0.4, "chain_long_enough": True},
            "unknowns": [{"path": "runout.road_friction", "name": "road friction", "kind": "dimensionless",
                          "ess": 120.0, "percentiles": {"p2.5": 0.6, "p50": 0.7, "p97.5": 0.8}}],
            "derived": [{"key": "speed.A", "kind": "speed", "percentiles": {"p2.5": 13.4112, "p50": 13.4112,
                                                                              "p97.5": 13.4112}}]}
    text = render_case_report(scene, input_files=[SCENE], system="US", mc=mc, posterior=post, figures=False,
                              output_kinds=OUTPUT_KINDS)
    p = _check(text)
    assert "monte-carlo" in p.ids and "posterior" in p.ids
    body = html.unescape(" ".join(p.text))
    mc_part = body[body.index("Monte Carlo"):body.index("Posterior")]
    head = mc_part[mc_part.index("Output"):]
    assert head.index("p5") < head.index("p50") < head.index("p95") < head.index("mean") < head.index("std")
    assert "30 mph" in mc_part and "75.0 %" in mc_part  # speed in mph, a fraction in % (as the text report)
    assert "0.75" not in mc_part
    post_part = body[body.index("Posterior"):]
    assert "road friction" in post_part and "0.7" in post_part and "30 mph" in post_part
    assert "chain short" in post_part


def test_a_rollover_statement_reads_as_a_verdict_in_the_evidence_table(tmp_path):
    """A rollover item is a statement, not a measurement: its row says what was computed and that the
    statement must hold (as the text report does), not a residual of 0 against a tolerance of 0."""
    text = SCENE.read_text().replace("[runout]\nroad_friction = 0.7\n",
                                     '[runout]\nroad_friction = 0.7\nlevel = "load_transfer"\nrollover = true\n', 1)
    assert "rollover = true" in text
    f = tmp_path / "roll.toml"
    f.write_text(text + '\n[[evidence.rollover]]\nunit = "car"\nrolled = false\nname = "car stayed upright"\n')
    scene = run_scene(load_scenario(f))
    page = render_case_report(scene, input_files=[f], figures=False)
    rows = [[html.unescape(re.sub(r"<[^>]+>", "", c)).strip() for c in re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)]
            for r in re.findall(r"<tr[^>]*>(.*?)</tr>", page, re.S) if "car stayed upright" in r]
    verdicts = [c for c in rows if c and c[0] in ("PASS", "FAIL")]
    assert len(verdicts) == 1
    cells = verdicts[0]
    assert "computed: does not roll" in cells and "the statement must hold" in cells
    assert cells[0] == "PASS"


def test_results_of_other_inputs_or_commands_are_refused(tmp_path, capsys):
    """A result embeds only beside the scene whose inputs made it (the SHA-256 of the scenario file
    and its survey files), and only as the result of its own command; one line, exit 2."""
    stamp = made_from("fit", SCENE)
    cases = {
        "no_stamp": ({"samples": 3}, "has no 'made_from'"),
        "other_command": ({"made_from": made_from("mc", SCENE)}, "is the result of crashsim mc, not of crashsim fit"),
        "other_inputs": ({"made_from": {**stamp, "inputs_sha256": "0" * 64}}, "was made from other inputs"),
    }
    for name, (obj, words) in cases.items():
        f = tmp_path / f"{name}.json"
        f.write_text(json.dumps(obj))
        out = tmp_path / f"{name}.html"
        assert main(["report", str(SCENE), "-o", str(out), "--fit", str(f)]) == 2, name
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and "--fit" in err and words in err, err
        assert not out.exists()
    # the scene file changed by one byte: its results no longer belong to it
    copy = tmp_path / "scene.toml"
    copy.write_bytes(SCENE.read_bytes())
    f = tmp_path / "fit.json"
    f.write_text(json.dumps({"made_from": made_from("fit", copy)}))
    copy.write_bytes(SCENE.read_bytes() + b"\n")
    assert main(["report", str(copy), "-o", str(tmp_path / "c.html"), "--fit", str(f)]) == 2
    assert "was made from other inputs" in capsys.readouterr().err


def test_a_result_of_this_scene_is_embedded(tmp_path, capsys):
    """crashsim mc --json stamps its result with the scene's inputs; the report takes it."""
    fit_scene_file = ROOT / "scenarios" / "fit" / "intersection_fit.toml"
    assert main(["mc", str(fit_scene_file), "--samples", "2", "--workers", "1", "--quiet", "--json"]) == 0
    out = capsys.readouterr().out
    doc = json.loads(out)
    assert doc["made_from"]["command"] == "mc"
    assert doc["made_from"]["inputs_sha256"] == made_from("mc", fit_scene_file)["inputs_sha256"]
    f = tmp_path / "mc.json"
    f.write_text(out)
    assert main(["report", str(fit_scene_file), "-o", str(tmp_path / "c.html"), "--mc", str(f)]) == 0
    assert main(["report", str(SCENE), "-o", str(tmp_path / "d.html"), "--mc", str(f)]) == 2
    assert "was made from other inputs" in capsys.readouterr().err


# -- the Monte Carlo section as an exhibit -----------------------------------------------------------

MC_FILE = ROOT / "scenarios" / "fit" / "intersection_fit.toml"


@pytest.fixture(scope="module")
def mc_result():
    """A small Monte Carlo of the shipped fit scene with acceptance, as ``crashsim mc --accept --json`` writes it."""
    from crashsim.motion.result import jsonable as _clean
    from crashsim.reconstruct.montecarlo import monte_carlo
    from crashsim.reconstruct.overrides import default_engine
    from crashsim.schema import load_toml

    mc = monte_carlo(load_toml(MC_FILE), n=12, engine=default_engine(), workers=1, progress=False, file=str(MC_FILE),
                     accept=True)
    return mc, json.loads(json.dumps(_clean(mc.to_dict())))


def _mc_section(text: str) -> str:
    return text[text.index('<section id="monte-carlo">'):text.index("</section>", text.index('id="monte-carlo"'))]


def test_monte_carlo_section_prints_no_data_structure_and_shares_in_percent(mc_result):
    from crashsim.reconstruct.montecarlo import OUTPUT_KINDS

    mc, d = mc_result
    assert isinstance(d["pass_share"], dict) and len(d["pass_share"]) > 2  # what was printed as a raw dict
    scene = run_scene(load_scenario(MC_FILE))
    text = render_case_report(scene, input_files=[MC_FILE], mc=d, figures=False, output_kinds=OUTPUT_KINDS)
    _check(text)
    section = _mc_section(text)
    shown = html.unescape(re.sub(r"<[^>]+>", " ", section))
    # no Python / JSON structure in the text: no braces, brackets of lists, quoted keys, None
    assert not re.search(r"[{}]|\[\s*'|'\s*:|\bNone\b|\bTrue\b|\bFalse\b", shown), shown[:800]
    # one row per evidence item, its share in % as the text report prints it ("  12.5 %  rest: ...")
    report = mc.report()
    for key, share in d["pass_share"].items():
        cell = f"{100 * share:.1f} %"
        assert re.search(rf"{re.escape(cell)}\s+{re.escape(key)}", report)  # the text report's line
        row = re.search(rf"<tr><td class=\"key\">{re.escape(str(_key_html(key)))}</td><td class=\"num\">([^<]*)</td>",
                        section)
        assert row and row[1] == cell, (key, row and row[1], cell)
    # the accepted samples: count, of how many, share in %
    acc = d["accepted"]
    assert f"{acc['count']} of {acc['of']} ({100 * acc['share']:.3g} %)" in shown
    assert mc.evidence_headline().startswith(f"{100 * acc['share']:.3g} % of {acc['of']} samples")
    # a fraction (energy loss) in % with the text report's digits, all and accepted
    qs = [q for q in d["percentiles"]["energy_loss.system"] if q.startswith("p")]
    lines = report.splitlines()
    i = next(j for j, ln in enumerate(lines) if ln.strip().startswith("energy_loss.system"))
    text_all = re.findall(r"-?\d+\.\d %", lines[i])
    assert text_all == [f"{100 * d['percentiles']['energy_loss.system'][q]:.1f} %" for q in qs]
    row = section[section.index(str(_key_html("energy_loss.system"))):]
    cells = re.findall(r'<td class="num">([^<]*)</td>', row)[:len(d["percentiles"]["energy_loss.system"])]
    assert cells[:len(qs)] == text_all
    assert all(c.endswith(" %") for c in cells)  # mean and std too


def _key_html(key):
    from crashsim.casereport import breakable_key

    return breakable_key(key)


def test_keys_wrap_only_at_their_separators():
    from crashsim.casereport import breakable_key

    assert str(breakable_key("vehicles.car.bodies[0].mass")) == "vehicles.<wbr>car.<wbr>bodies<wbr>[0].<wbr>mass"
    assert str(breakable_key("speed_at_braking.A")) == "speed_<wbr>at_<wbr>braking.<wbr>A"
    assert str(breakable_key("a<b")) == "a&lt;b"  # escaped
    css = (ROOT / "src" / "crashsim" / "templates" / "case_report.html.j2").read_text()
    rule = re.search(r"td\.key, table\.inputs td\.key \{([^}]*)\}", css)
    assert rule and "break-word" in rule[1] and "anywhere" not in rule[1] and "break-all" not in rule[1]


_BREAKS = """<script>window.addEventListener("load", () => {
  // where the browser broke each key cell's text into lines: the characters either side of each break
  const out = [];
  for (const td of document.querySelectorAll("td.key")) {
    const text = td.textContent; const walker = document.createTreeWalker(td, NodeFilter.SHOW_TEXT);
    const chars = []; let n;
    while ((n = walker.nextNode())) for (let i = 0; i < n.length; i++) {
      const r = document.createRange(); r.setStart(n, i); r.setEnd(n, i + 1);
      const b = r.getClientRects(); if (b.length) chars.push([n.data[i], b[0].top]);
    }
    for (let i = 1; i < chars.length; i++)
      if (chars[i][1] > chars[i - 1][1] + 2) out.push([text, chars[i - 1][0], chars[i][0]]);
  }
  document.body.setAttribute("data-breaks", JSON.stringify(out));
});</script>"""


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium on this machine (Debian: apt-get install chromium); "
                                             ".ci/run installs it")
def test_chromium_breaks_keys_at_separators_not_mid_word(mc_result, tmp_path):
    """Laid out narrow (500 px, where long keys must wrap), every line break inside a key cell falls after a
    separator (., _, /, -, a space) or before a "[": never between two letters of a word."""
    from crashsim.reconstruct.montecarlo import OUTPUT_KINDS

    _, d = mc_result
    scene = run_scene(load_scenario(MC_FILE))
    page = tmp_path / "case.html"
    page.write_text(render_case_report(scene, input_files=[MC_FILE], mc=d, figures=False,
                                       output_kinds=OUTPUT_KINDS).replace("</body>", _BREAKS + "</body>"),
                    encoding="utf-8")
    base = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={tmp_path / 'profile'}",
            "--host-resolver-rules=MAP * ~NOTFOUND"]
    dom = subprocess.run(base + ["--window-size=500,1400", "--virtual-time-budget=5000", "--dump-dom",
                                 page.resolve().as_uri()], check=True, capture_output=True, text=True,
                         timeout=180).stdout
    found = re.search(r'data-breaks="([^"]*)"', dom)
    assert found, "the probe did not run"
    breaks = json.loads(html.unescape(found[1]))
    assert len(breaks) >= 5, "the narrow page wraps some keys (else this test measures nothing)"
    bad = [(text, a, b) for text, a, b in breaks if not (a in "._/- " or b == "[")]
    assert not bad, bad[:10]


SURVEY_SCENE = ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml"


class _Table(HTMLParser):
    """The rows (cell texts) of the table inside the element with id ``section``."""

    def __init__(self, section: str):
        super().__init__(convert_charrefs=True)
        self.section, self.depth, self.rows, self.cell = section, 0, [], None

    def handle_starttag(self, tag, attrs):
        if self.depth:
            self.depth += tag not in VOID
        elif dict(attrs).get("id") == self.section:
            self.depth = 1
        if self.depth and tag == "tr":
            self.rows.append([])
        if self.depth and tag in ("td", "th"):
            self.cell = []

    def handle_endtag(self, tag):
        if not self.depth:
            return
        if tag in ("td", "th") and self.cell is not None:
            self.rows[-1].append("".join(self.cell).strip())
            self.cell = None
        self.depth -= 1

    def handle_data(self, data):
        if self.cell is not None:
            self.cell.append(data)


def test_a_posterior_s_energy_loss_is_a_percentage(tmp_path):
    """A derived fraction of the posterior (an energy loss) in %, as the text report and the Monte Carlo
    section print it (it was a bare fraction, 0.43); a dimensionless unknown (a friction) stays a number."""
    scene = run_scene(load_scenario(SCENE))
    post = {"success": True, "message": "ok", "warnings": [],
            "diagnostics": {"samples": 100, "acceptance_mean": 0.4, "chain_long_enough": True},
            "unknowns": [{"path": "runout.road_friction", "name": "road friction", "kind": "dimensionless",
                          "ess": 120.0, "percentiles": {"p2.5": 0.61, "p50": 0.7, "p97.5": 0.8}}],
            "derived": [{"key": "energy_loss.system", "kind": "dimensionless",
                         "percentiles": {"p2.5": 0.3874, "p50": 0.43, "p97.5": 0.4676}}]}
    text = render_case_report(scene, input_files=[SCENE], system="US", posterior=post, figures=False)
    rows = {r[0]: r[1:] for r in _table_rows(text, "posterior") if r}
    assert rows["energy_loss.system"][:3] == ["38.7 %", "43.0 %", "46.8 %"], rows
    assert rows["road friction"][:3] == ["0.61", "0.7", "0.8"], rows


def test_preset_values_are_in_the_report_s_units():
    """A US report lists the geometry a body takes from a preset in ft (the library writes m; it showed
    m); its SI column and the file's own values are unchanged, and an SI report keeps the library's text."""
    import tomllib

    scene = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
    text = scene.read_text(encoding="utf-8")
    raw, sc = tomllib.loads(text), load_scenario(scene)
    us = {r["key"]: r for r in input_rows(raw, toml_comments(text), sc.data, presets(), "US")}
    si = {r["key"]: r for r in input_rows(raw, toml_comments(text), sc.data, presets(), "SI")}
    length = "vehicles.truck.bodies[0].length"
    assert us[length]["origin"] == "preset tractor-3axle"
    assert (us[length]["value"], us[length]["unit"], us[length]["si"]) == ("27.23 ft", "ft", "8.3")
    assert (si[length]["value"], si[length]["unit"]) == ('"8.30 m"', "m")
    hitch = us["vehicles.truck.bodies[0].rear_hitch"]
    assert (hitch["value"], hitch["unit"]) == ("[-10.17 ft, 0 ft]", "ft")
    assert us["vehicles.truck.bodies[0].mass"]["value"] == "20944 lb"  # 5 digits, not 2.094e+04
    own = [k for k, r in us.items() if r["origin"] == "file" and r["unit"]]
    assert own and all(us[k]["value"] == si[k]["value"] for k in own)  # the file's values as written


def _table_rows(text: str, section: str) -> list[list[str]]:
    p = _Table(section)
    p.feed(text)
    return p.rows


def test_survey_provenance_names_the_source_of_every_imported_item():
    from crashsim.survey.report import survey_records

    scene = run_scene(load_scenario(SURVEY_SCENE))
    records = survey_records(scene.scenario)
    assert len(records) >= 20  # the shipped survey: two files, a recorder table and an orthophoto
    text = render_case_report(scene, input_files=[SURVEY_SCENE], figures=False)
    _check(text)
    head, *rows = _table_rows(text, "survey-provenance")
    assert head == ["File", "Layer or code", "Entity", "Became", "Scene item", "Map entry", "Note"]
    assert len(rows) == len(records)  # one row per imported record, in their order
    made = {r["target"] for r in records if r["target"] and r["kind"] != "warning"}
    body = html.unescape(re.sub(r"<[^>]+>", "", text))
    assert f"made {len(made)} scene items" in re.sub(r"\s+", " ", body)
    for row, r in zip(rows, records):
        assert row[0] == r["file"] and row[1] == r["layer"], (row, r)
        assert row[2] == f"{r['type']} {r['ref']}".strip()
        assert row[4].startswith(r["target"]) and row[5] == r["key"]
    by_target = {row[4]: row for row in rows if row[4]}
    mark = next(v for k, v in by_target.items() if k.startswith("evidence.marks[0]"))
    assert mark[:4] == ["files/scene.dxf", "SKID-TRACTOR-L", "LWPOLYLINE 9C", "mark"]
    assert "pre-impact skid" in mark[4]  # the item's name, from the label text of its layer
    assert any(row[0] == "files/points.csv" and row[1] == "CAR REST" and row[4].startswith("evidence.rest[2]")
               for row in rows)
    assert any(row[0] == "files/ecm.csv" and row[4].startswith("evidence.recorder[0]") for row in rows)
    # the notes of the import are rows too (the drawing's units as read)
    assert any(row[3] == "note of the import" and "INSUNITS" in row[6] for row in rows)


def test_a_scene_without_survey_has_no_provenance_section():
    scene = run_scene(load_scenario(SCENE))
    text = render_case_report(scene, input_files=[SCENE], figures=False)
    assert "survey-provenance" not in _check(text).ids
    assert "Survey provenance" not in text


FIGURE_SCENE = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"  # approach and run-out: every figure


@pytest.fixture(scope="module")
def report_figs():
    import matplotlib.pyplot as plt

    from crashsim.casereport import report_figures

    scene = run_scene(load_scenario(FIGURE_SCENE))
    figs = report_figures(scene, "US")
    for f in figs:
        f["figure"].draw_without_rendering()
    yield scene, figs
    for f in figs:
        plt.close(f["figure"])


def _texts(fig):
    """The texts a figure draws: visible, not empty, not the labels of ticks outside the view (matplotlib
    keeps those, and does not draw them)."""
    from matplotlib.text import Text

    undrawn = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            tol = 1e-9 * max(abs(lo), abs(hi), 1.0)
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                if not lo - tol <= tick.get_loc() <= hi + tol:
                    undrawn |= {id(tick.label1), id(tick.label2)}
    return [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip() and id(t) not in undrawn]


def test_report_figures_type_is_at_least_7_pt_as_shown(report_figs):
    from crashsim.casereport import FIGURE_DISPLAY_MM, MIN_TEXT_PT, figure_scale

    scene, figs = report_figs
    assert [f["id"] for f in figs] == ["scene", "scene-approach", "histories", "time-distance", "wheels"]
    small = []
    for f in figs:
        fig = f["figure"]
        scale = figure_scale(fig)
        assert scale == pytest.approx(FIGURE_DISPLAY_MM / 25.4 / fig.get_size_inches()[0])
        texts = _texts(fig)
        assert len(texts) > 10, f["id"]
        small += [(f["id"], t.get_text()[:30], round(t.get_fontsize() * scale, 2)) for t in texts
                  if t.get_fontsize() * scale < MIN_TEXT_PT]
    assert MIN_TEXT_PT == 7.0
    assert not small, small
    # the page shows every figure at that width (its CSS), within the print width of A4 (182 mm)
    text = render_case_report(scene, input_files=[FIGURE_SCENE], figures=False)
    assert f"figure img {{ width: {FIGURE_DISPLAY_MM:g}mm;" in text
    assert FIGURE_DISPLAY_MM <= 182.0


def test_report_figures_clip_no_text(report_figs):
    _, figs = report_figs
    out = []
    for f in figs:
        fig = f["figure"]
        r = fig.canvas.get_renderer()
        w, h = fig.bbox.width, fig.bbox.height
        for t in _texts(fig):
            bb = t.get_window_extent(r)
            if bb.x0 < -1 or bb.y0 < -1 or bb.x1 > w + 1 or bb.y1 > h + 1:
                out.append((f["id"], t.get_text()[:40], [round(v) for v in bb.extents], (round(w), round(h))))
    assert not out, out


def test_plot_figures_keep_their_own_size():
    """The report's figure width is the report's: ``crashsim plot`` figures keep 10 in (scene), 10.5 in
    (time-distance); a width outside its range is refused, naming it."""
    import matplotlib.pyplot as plt

    from crashsim.errors import ScenarioError
    from crashsim.plotting import MAX_WIDTH, MIN_WIDTH, plot_scene, plot_time_distance

    scene = run_scene(load_scenario(SCENE))
    ax = plot_scene(scene)
    assert ax.figure.get_size_inches()[0] == pytest.approx(10.0)
    fig = plot_time_distance(scene)
    assert tuple(fig.get_size_inches()) == pytest.approx((10.5, 6.5))
    plt.close("all")
    with pytest.raises(ScenarioError, match=r"width = 1 in is outside the allowed 3 to 40 in") as exc:
        plot_scene(scene, width=1)
    assert exc.value.field == "width" and (MIN_WIDTH, MAX_WIDTH) == (3.0, 40.0)
    with pytest.raises(ScenarioError, match="leave ax=None"):
        plot_scene(scene, width=6.0, paper="A4")
