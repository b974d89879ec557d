"""Write the shipped table of SI unit factors, ``src/crashsim/data/unit_factors.json``.

    python benchmarks/unit_factors.py

The table holds pint's SI factor of every documented unit spelling and display label of every
quantity kind (:func:`crashsim.units.factor_table`), so that a scene file in those units is read
without importing pint. Run it after changing a kind's spellings or labels, or pint's version;
``tests/unit/test_units.py`` fails until the table agrees with pint.
"""

from __future__ import annotations

import json
from pathlib import Path

from crashsim.units import factor_table

OUT = Path(__file__).resolve().parents[1] / "src" / "crashsim" / "data" / "unit_factors.json"


def main() -> int:
    OUT.write_text(json.dumps(factor_table(), indent=1) + "\n", encoding="utf-8")
    print(f"wrote {OUT.relative_to(OUT.parents[3])}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
