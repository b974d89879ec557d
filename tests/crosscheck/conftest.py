"""The cross-check tier reuses the analytic tier's vehicles (tests/analytic/runout_cases.py)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "analytic"))
