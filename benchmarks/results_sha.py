"""Results unchanged: the SHA-256 of every shipped scene's JSON result on both engines, and of the
fit, Monte Carlo and posterior of the shipped fit scene, so that a restructuring of the code can be
shown to leave every result byte-identical (issue 32).

Not a test: the hashes are digit-for-digit, so they hold on one machine (compiled code differs in
its last bits between processors) and are compared there, before and after a change:

    python benchmarks/results_sha.py --out /tmp/before.json          # on the old code
    python benchmarks/results_sha.py --out /tmp/after.json --compare /tmp/before.json

``--quick`` leaves out the scipy engine's runs and the posterior (minutes instead of tens of
minutes). Timing fields (CPU and elapsed seconds) are removed from a JSON before it is hashed;
nothing else is; files are named relative to the repository root, so checkouts at other paths
compare. Run it with the kernels compiled (a first run in a new checkout runs a single scene
interpreted while they compile: other last bits). Exit code 1 when ``--compare`` finds a difference.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import sys
from pathlib import Path

from crashsim.cli import main as crashsim

ROOT = Path(__file__).resolve().parents[1]
FIT = "scenarios/fit/intersection_fit.toml"
#: Keys of a JSON result that measure the machine, not the model.
TIMING = {"cpu_s", "elapsed_s", "cpu_time", "elapsed", "wall_s", "wall_time", "seconds", "cpu_seconds",
          "elapsed_seconds", "time_s", "rate", "evaluations_per_s"}


def _strip(node):
    if isinstance(node, dict):
        return {k: _strip(v) for k, v in node.items() if k not in TIMING}
    if isinstance(node, list):
        return [_strip(v) for v in node]
    return node


def _run(args: list[str]) -> tuple[int, str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = crashsim(args)
    return code, out.getvalue()


def _digest(data) -> str:
    return hashlib.sha256(json.dumps(_strip(data), sort_keys=True).encode()).hexdigest()


def _sha(args) -> str:
    if callable(args):  # a scene on one engine, through the API
        return _digest(args())
    try:
        code, text = _run(args)
    except SystemExit as exc:  # an option this version does not have
        return f"exit {exc.code}"
    if code:
        return f"exit {code}"
    try:
        return _digest(json.loads(text))
    except json.JSONDecodeError:
        return "not JSON: " + hashlib.sha256(text.encode()).hexdigest()


def _scene_json(path: str, engine: str):
    """The JSON result of ``crashsim run --json`` with the run-out on ``engine``."""
    from dataclasses import replace

    from crashsim.motion.result import jsonable
    from crashsim.scenario import load_scenario
    from crashsim.scene.run import run_scene

    sc = load_scenario(path)  # relative to the root, as in the CLI's runs: the JSON names the file as given
    if sc.runout is not None:
        sc = replace(sc, runout=replace(sc.runout, options=replace(sc.runout.options, engine=engine)))
    return jsonable(run_scene(sc).to_dict())


def jobs(quick: bool) -> dict:
    scenes = sorted(str(p.relative_to(ROOT)) for d in ("scenes", "paper", "survey", "fit")
                    for p in (ROOT / "scenarios" / d).glob("*.toml"))
    out = {}
    for s in scenes:
        out[f"run {s}"] = ["run", s, "--json"]
        for engine in ("compiled",) if quick else ("compiled", "scipy"):
            out[f"run-out {engine} {s}"] = (lambda s=s, e=engine: _scene_json(s, e))
    out[f"fit {FIT}"] = ["fit", FIT, "--json", "--workers", "1"]
    out[f"mc {FIT}"] = ["mc", FIT, "--json", "--samples", "200", "--workers", "1", "--quiet"]
    if not quick:
        out[f"posterior {FIT}"] = ["posterior", FIT, "--json", "--steps", "400", "--workers", "1", "--quiet"]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="write the hashes (JSON) here")
    ap.add_argument("--compare", help="hashes written before: print what differs")
    ap.add_argument("--quick", action="store_true", help="compiled engine only, no posterior")
    ap.add_argument("--only", help="only the jobs whose name contains this text")
    a = ap.parse_args(argv)
    os.chdir(ROOT)  # every file named relative to the root: the hashes do not depend on the checkout's path
    hashes = {}
    for name, args in jobs(a.quick).items():
        if a.only and a.only not in name:
            continue
        hashes[name] = _sha(args)
        print(f"{hashes[name][:16]}  {name}", file=sys.stderr)
    Path(a.out).write_text(json.dumps(hashes, indent=1, sort_keys=True) + "\n")
    if not a.compare:
        return 0
    before = json.loads(Path(a.compare).read_text())
    differ = [k for k in hashes if k in before and before[k] != hashes[k]]
    for k in differ:
        print(f"DIFFERS  {k}")
    print(f"{len(hashes) - len(differ)} of {len(hashes)} unchanged"
          + (f" ({len([k for k in hashes if k not in before])} not in the file compared)" if any(
              k not in before for k in hashes) else ""))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
