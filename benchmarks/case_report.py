"""Regenerate plots/case_report.png: the first screen of the case report of a shipped scene
(``crashsim report``), as a real headless Chromium renders it, and plots/case_report.pdf's page
count (printed; the PDF itself is not committed).

Run from the repository root: ``python benchmarks/case_report.py`` (needs Chromium: Debian
``apt-get install chromium``). The report is written to a temporary folder; the date in it is
the day it is run.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from crashsim.cli import main as crashsim

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
OUT = ROOT / "plots" / "case_report.png"


def main() -> int:
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        print("no Chromium on this machine (Debian: apt-get install chromium)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        html = Path(tmp) / "case.html"
        # relative to the repository root, as a user in a checkout would name it
        code = crashsim(["report", str(SCENE.relative_to(ROOT)), "-o", str(html), "--units", "US"])
        if code:
            return code
        base = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={tmp}/profile",
                "--host-resolver-rules=MAP * ~NOTFOUND", "--hide-scrollbars"]
        subprocess.run(base + [f"--screenshot={OUT}", "--window-size=1000,1500", html.as_uri()], check=True,
                       capture_output=True, timeout=300)
        pdf = Path(tmp) / "case.pdf"
        subprocess.run(base + [f"--print-to-pdf={pdf}", "--no-pdf-header-footer", html.as_uri()], check=True,
                       capture_output=True, timeout=300)
        pages = len(re.findall(rb"/Type\s*/Page[^s]", pdf.read_bytes()))
    print(f"wrote {OUT.relative_to(ROOT)} (the report prints on {pages} pages, US letter)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
