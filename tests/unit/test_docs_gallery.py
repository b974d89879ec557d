"""The site's executed examples (docs/_ext/crashsim_examples.py, the ``crashsim-example`` directive of
docs/gallery.md): a good scene gives its report and a figure drawn by that run; a broken one is an
error, and a Sphinx build with ``-W`` (the CI command) fails on it."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXT = ROOT / "docs" / "_ext" / "crashsim_examples.py"
PNG = b"\x89PNG\r\n\x1a\n"


def _module():
    spec = importlib.util.spec_from_file_location("crashsim_examples", EXT)
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("crashsim_examples", module)
    spec.loader.exec_module(module)
    return module


ex = _module()

GOOD = """\
import crashsim

scene = crashsim.run("scenarios/scenes/car_trailer_side_impact.toml")
print(scene.report())
scene.plot()
"""


def test_a_good_scene_gives_its_report_and_its_figure(tmp_path):
    example = ex.run_example(GOOD, "good", tmp_path)
    assert example.output.startswith("crashsim: Car towing a trailer struck on the side"), example.output[:200]
    assert "file: scenarios/scenes/car_trailer_side_impact.toml" in example.output
    [figure] = example.figures
    assert figure == tmp_path / "good-1.png"
    data = figure.read_bytes()
    assert data.startswith(PNG) and len(data) > 10_000
    import matplotlib.pyplot as plt

    assert plt.get_fignums() == []  # each figure saved and closed


def test_a_broken_scene_raises_with_its_traceback(tmp_path):
    broken = tmp_path / "broken.toml"
    shutil.copy(ROOT / "scenarios" / "scenes" / "car_trailer_side_impact.toml", broken)
    text = broken.read_text()
    assert '\nspeed = "' in text
    broken.write_text(text.replace('\nspeed = "', '\nspeed = "a mass of 40 kg, not a speed" # "', 1))
    code = f"import crashsim\ncrashsim.run({str(broken)!r}).plot()\n"
    with pytest.raises(ex.ExampleError, match=r"(?s)raised:.*Scenario\w*Error: [^\n]*broken\.toml: vehicles\.\w+\.speed"):
        ex.run_example(code, "broken", tmp_path)
    assert not list(tmp_path.glob("broken-*.png"))


def test_a_warning_is_an_error_too(tmp_path):
    with pytest.raises(ex.ExampleError, match="(?s)warned:.*UserWarning: stale number"):
        ex.run_example("import warnings\nwarnings.warn('stale number')\n", "warns", tmp_path)


def test_an_example_name_that_cannot_name_a_file_is_refused(tmp_path):
    with pytest.raises(ValueError, match="example name"):
        ex.run_example("print(1)\n", "../up", tmp_path)


def test_named_files_are_the_scenes_the_code_reads():
    assert ex.named_files(GOOD) == [ROOT / "scenarios" / "scenes" / "car_trailer_side_impact.toml"]


def test_the_build_with_warnings_as_errors_fails_on_a_broken_example(tmp_path):
    """A two-page site (no autodoc, no scene run: the broken file is refused as it is read), built by
    the CI command: the failing example is reported at its line and the build exits non-zero."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        f"import sys\nsys.path.insert(0, {str(EXT.parent)!r})\n"
        "extensions = ['myst_parser', 'crashsim_examples']\nexclude_patterns = ['_build']\n")
    (src / "index.md").write_text("# Site\n\n```{toctree}\nbad\n```\n")
    (src / "bad.md").write_text("# Bad\n\n```{crashsim-example} bad\nimport crashsim\n"
                                "crashsim.run('no/such/scene.toml')\n```\n")
    build = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(src),
                            str(tmp_path / "html")], capture_output=True, text=True, cwd=ROOT)
    assert build.returncode != 0
    assert "bad.md:3" in build.stderr and "crashsim-example bad failed" in build.stderr, build.stderr
    assert "no/such/scene.toml" in build.stderr


def test_the_gallery_shows_every_shipped_scene_and_runs_examples():
    """The committed figures of every shipped scene are on the page, and some examples run at build."""
    page = (ROOT / "docs" / "gallery.md").read_text()
    scenes = sorted((ROOT / "scenarios" / "scenes").glob("*.toml")) + sorted((ROOT / "scenarios" / "survey").glob("*.toml"))
    missing = [s.stem for s in scenes if f"../plots/scene_{s.stem}.png" not in page]
    assert not missing, missing
    for s in scenes:
        assert (ROOT / "plots" / f"scene_{s.stem}.png").is_file(), s.stem
    examples = [ln.split()[1] for ln in page.splitlines() if ln.startswith("```{crashsim-example}")]
    assert len(examples) >= 4 and len(set(examples)) == len(examples), examples
    assert "```{crashsim-example} validation-" in page


def test_the_validation_example_gives_computed_against_measured(tmp_path):
    """The gallery's validation case: its table row (measured, computed, error, band) and its figure,
    which ``plot_case`` returns open when given no path (and writes and closes when given one)."""
    from crashsim.validation import load_suite, plot_case, run_suite

    code = ("from crashsim.validation import load_suite, plot_case, run_suite, table_text\n"
            "[case] = run_suite(load_suite(), ['j695-offtracking'])\nprint(table_text([case]))\nplot_case(case)\n")
    example = ex.run_example(code, "j695", tmp_path)
    [row] = [ln for ln in example.output.splitlines() if ln.startswith("j695-offtracking ")]
    assert row.split()[-1] == "within" and row.count(" ft") >= 2, row
    [figure] = example.figures
    assert figure.read_bytes().startswith(PNG)
    import matplotlib.pyplot as plt

    [case] = run_suite(load_suite(), ["j695-offtracking"])
    fig = plot_case(case)
    try:
        assert fig.get_suptitle().startswith("j695-offtracking: ")
    finally:
        plt.close(fig)
    assert plot_case(case, tmp_path / "j695.png") == tmp_path / "j695.png"
    assert (tmp_path / "j695.png").read_bytes().startswith(PNG) and plt.get_fignums() == []
