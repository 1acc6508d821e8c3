#!/usr/bin/env python3
"""Runs the shipped cases with two builds of tessera and compares what they report, bit for bit.

For refactorings that must change no result (issue 14): every quantity in summary.json and, for the
flow cases, every column of series.csv must be identical. Keys named with --allow may differ in the
last digits only (relative 1e-12): sums whose reduction became canonical.

  git worktree add /tmp/before OLD_COMMIT   # its case files, for the BEFORE binary
  tools/check_same_results.py BEFORE_BIN AFTER_BIN --before-root /tmp/before
                              [--cases deposition,grain_bed,bunker,flow] [--allow kinetic_energy,...]
                              [--ranks 2] [--work /tmp/same] [--only-before | --reuse-before]

Cases (2 ranks, about 12 minutes per binary on 2 cores in all):
  deposition  cases/deposition/small.yaml, to settled
  grain_bed   cases/grain_bed/small.yaml, first 0.03 s
  hertz       cases/deposition/paper.yaml in a 20 mm box, first 15 ms (Hertz-Mindlin; contacts from 8 ms)
  bunker      the small pipeline: bed_small (to settled), ball_small, relax_small, small (the shot)
  flow        dam_break/martin_moyce (0.05 s), drop_impact/seed_floor, seed_pool and pool_bench (1 ms)
Exit code 0 when everything matches, 1 otherwise.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# name -> list of (output subdir, case, extra --set overrides); later runs read earlier checkpoints.
CASES = {
    "deposition": [("deposition", "cases/deposition/small.yaml", [])],
    "grain_bed": [("grain_bed", "cases/grain_bed/small.yaml", ["run.end_time=0.03"])],
    # The Hertz-Mindlin law (no small case uses it): the paper deposition cut to a 20 mm box, 15 ms.
    "hertz": [("hertz", "cases/deposition/paper.yaml",
               ["domain.box_max=[20 mm, 3 mm, 20 mm]", "solid.walls.0.max=[20 mm, 3 mm, 20 mm]",
                "deposition.region_max=[20 mm, 3 mm, 19 mm]", "run.end_time=15e-3", "output.checkpoint_interval=0"])],
    "bunker": [
        ("bunker_bed", "cases/bunker_shot/bed_small.yaml", []),
        ("bunker_ball", "cases/bunker_shot/ball_small.yaml", ["bed.file={work}/bunker_bed/checkpoint.h5"]),
        ("bunker_relax", "cases/bunker_shot/relax_small.yaml", ["bed.file={work}/bunker_ball/checkpoint.h5"]),
        ("bunker_shot", "cases/bunker_shot/small.yaml", ["bed.file={work}/bunker_relax/checkpoint.h5"]),
    ],
    "flow": [
        ("dam_break", "cases/dam_break/martin_moyce.yaml", ["run.end_time=0.05"]),
        ("seed_floor", "cases/drop_impact/seed_floor.yaml", ["run.end_time=1e-3"]),
        ("seed_pool", "cases/drop_impact/seed_pool.yaml", ["run.end_time=1e-3"]),
        ("pool_bench", "cases/drop_impact/pool_bench.yaml", ["run.end_time=1e-3"]),
    ],
}
# Keys that are not results (timing, paths, counters of work done).
IGNORED = {"wall_time", "loop_time", "timers", "case", "version", "output_dir"}


def run(binary, root, ranks, case, sets, out):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", CI="1")
    path = Path(root) / case
    # The flow scene before 2026-11-29 named its snapshot interval field_interval.
    text = path.read_text()
    old_flow = "field_interval" in text or ("fluid:" in text and Path(root).resolve() != ROOT)
    key = "field_interval" if old_flow else "snapshot_interval"
    cmd = ["mpirun", "-n", str(ranks), binary, "run", str(path), "--quiet", "--output", str(out),
           "--set", f"output.{key}=0"]
    for s in sets:
        cmd += ["--set", s.format(work=out.parent)]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")


def same_number(a, b, allowed):
    if a == b:
        return True
    if allowed and isinstance(a, float) and isinstance(b, float):
        return abs(a - b) <= 1e-12 * max(abs(a), abs(b))
    return False


def compare_json(a, b, path, allow, out):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k in IGNORED:
                continue
            if k not in a or k not in b:
                out.append(f"{path}{k}: only in {'after' if k in b else 'before'}")
                continue
            compare_json(a[k], b[k], f"{path}{k}.", allow, out)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            compare_json(x, y, f"{path}{i}.", allow, out)
    elif not same_number(a, b, path.rstrip(".").split(".")[-1] in allow or path.split(".")[0] in allow):
        out.append(f"{path.rstrip('.')}: before {a!r} after {b!r}")


def compare_series(a, b, allow, out):
    if not a.exists():
        return
    ra, rb = list(csv.DictReader(open(a))), list(csv.DictReader(open(b)))
    if len(ra) != len(rb):
        out.append(f"series.csv: {len(ra)} rows before, {len(rb)} after")
        return
    for i, (x, y) in enumerate(zip(ra, rb)):
        for k in x:
            if x[k] != y.get(k) and not (k in allow and same_number(float(x[k]), float(y[k]), True)):
                out.append(f"series.csv row {i} {k}: before {x[k]} after {y.get(k)}")
                return


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--allow", default="")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--work", default="/tmp/tessera_same")
    ap.add_argument("--reuse-before", action="store_true",
                    help="keep the BEFORE runs already in --work (a summary.json there): run only AFTER")
    ap.add_argument("--only-before", action="store_true",
                    help="run only the BEFORE binary (while the change is being written), compare nothing")
    ap.add_argument("--before-root", default=str(ROOT),
                    help="the checkout whose case files the BEFORE binary reads (git worktree of the old commit)")
    a = ap.parse_args()
    allow = set(filter(None, a.allow.split(",")))
    failed = False
    for name in a.cases.split(","):
        for sub, case, sets in CASES[name]:
            results = {}
            for label, binary, root in (("before", a.before, a.before_root), ("after", a.after, ROOT)):
                out = Path(a.work) / label / sub
                results[label] = out
                if label == "after" and a.only_before:
                    continue
                if label == "before" and a.reuse_before and (out / "summary.json").exists():
                    continue
                run(os.path.abspath(binary), root, a.ranks, case, sets, out)
            if a.only_before:
                print(f"{sub:14s} before done", flush=True)
                continue
            diffs = []
            sa = json.load(open(results["before"] / "summary.json"))
            sb = json.load(open(results["after"] / "summary.json"))
            compare_json(sa.get("quantities", {}), sb.get("quantities", {}), "", allow, diffs)
            compare_json(sa.get("steps"), sb.get("steps"), "steps.", allow, diffs)
            compare_series(results["before"] / "series.csv", results["after"] / "series.csv", allow, diffs)
            print(f"{sub:14s} {'same' if not diffs else 'DIFFERS'}", flush=True)
            for d in diffs[:10]:
                print(f"    {d}")
            failed = failed or bool(diffs)
    print("all the same" if not failed else "some results differ")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
