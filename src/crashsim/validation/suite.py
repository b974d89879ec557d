"""Finding, loading and running the validation suite (``validation/`` at the repository's root).

Where the suite is. The suite is the repository's evidence, versioned with the code, the docs and the
published error table, so it is not copied into the installed package (a copy would drift from the
table a report quotes). :func:`find_suite` takes, in order: the folder given (``--suite DIR``); a
``validation/`` folder with a ``rules.toml`` in the current directory (``pip install . && crashsim
validate`` from a clone's root); the ``validation/`` folder of the source checkout this package runs
from (an editable install). Anything else is an input error naming ``--suite``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import ScenarioError
from ..schema import load_toml
from . import barrier, glance, offtracking, ricsac, stopping
from .core import CaseResult, read_case

__all__ = ["find_suite", "Suite", "load_suite", "run_suite", "KINDS", "TIERS"]

#: Case kinds, the module that runs each, and its cost tier (fast: impact solves and short run-outs,
#: seconds; slow: run-outs to rest of several vehicles or many of them, tens of seconds).
KINDS = {"staged_collision": "ricsac", "barrier_test": "barrier", "barrier_sequence": "glance",
         "stopping_distance": "stopping", "offtracking": "offtracking"}
TIERS = ("fast", "slow")


def find_suite(path=None) -> Path:
    """The suite's folder (module docstring); a :class:`ScenarioError` (field ``--suite``) if none is found."""
    if path is not None:
        p = Path(path)
        if not (p / "rules.toml").is_file():
            raise ScenarioError(f"{str(path)!r} is not a validation suite (no rules.toml in it); give the repository's "
                                "validation/ folder", field="--suite")
        return p
    for p in (Path.cwd() / "validation", Path(__file__).resolve().parents[3] / "validation"):
        if (p / "rules.toml").is_file():
            return p
    raise ScenarioError("no validation suite found: run from the repository's root (its validation/ folder) or give "
                        "--suite DIR", field="--suite")


@dataclass(frozen=True)
class Suite:
    """The suite's folder, its rules and its cases' data (``measured.toml`` and ``record.toml``) by id."""

    folder: Path
    rules: dict
    cases: dict

    def select(self, ids=None, tier: str | None = None) -> list[str]:
        """Case ids to run: those named (each must exist), else all; only ``tier``'s if given."""
        if ids:
            unknown = [i for i in ids if i not in self.cases]
            if unknown:
                raise ScenarioError(f"unknown case {', '.join(map(repr, unknown))}; allowed {', '.join(self.cases)}",
                                    field="CASE")
            chosen = list(dict.fromkeys(ids))
        else:
            chosen = list(self.cases)
        if tier is not None:
            chosen = [i for i in chosen if self.cases[i]["case"].get("tier", "fast") == tier]
        return chosen


def load_suite(path=None) -> Suite:
    """Read the suite: ``rules.toml`` and every case folder (one with a ``measured.toml``), sorted by id."""
    folder = find_suite(path)
    rules = load_toml(folder / "rules.toml")
    cases = {}
    for sub in sorted(p for p in folder.iterdir() if (p / "measured.toml").is_file()):
        data = read_case(sub)
        kind = data["case"]["kind"]
        if kind not in KINDS:
            raise ScenarioError(f"case.kind = {kind!r}; allowed {', '.join(KINDS)}", field="case.kind",
                                file=str(sub / "measured.toml"))
        tier = data["case"].get("tier", "fast")
        if tier not in TIERS:
            raise ScenarioError(f"case.tier = {tier!r}; allowed {', '.join(TIERS)}", field="case.tier",
                                file=str(sub / "measured.toml"))
        cases[data["case"]["id"]] = data
    if not cases:
        raise ScenarioError(f"{str(folder)!r} holds no case (no folder with a measured.toml)", field="--suite")
    return Suite(folder, rules, cases)


def _runner(kind: str):
    return {"ricsac": ricsac, "barrier": barrier, "glance": glance, "stopping": stopping,
            "offtracking": offtracking}[KINDS[kind]]


def run_suite(suite: Suite, ids=None, *, tier: str | None = None, progress=None) -> list[CaseResult]:
    """Run the chosen cases (all by default); ``progress(case_id)`` is called before each."""
    chosen = suite.select(ids, tier)
    same_kind = {}
    for cid, data in suite.cases.items():
        same_kind.setdefault(data["case"]["kind"], []).append(data)
    results = []
    for cid in chosen:
        if progress is not None:
            progress(cid)
        data = suite.cases[cid]
        kind = data["case"]["kind"]
        module = _runner(kind)
        t0 = time.process_time()
        if kind == "staged_collision":
            tests = [module.load_test(d) for d in same_kind[kind]]
            result = module.run_case(data, suite.rules, tests)
        else:
            result = module.run_case(data, suite.rules, suite.folder)
        results.append(result if result.cpu_seconds else _with_cpu(result, time.process_time() - t0))
    return results


def _with_cpu(result: CaseResult, cpu: float) -> CaseResult:
    return replace(result, cpu_seconds=cpu)
