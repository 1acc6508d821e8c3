#!/usr/bin/python3
"""Strong scaling of a case: runs it on a list of rank counts (here, or as Slurm jobs), then gathers
each run's summary.json into speed-up, parallel efficiency and the time per phase (the seeds' Fig.
10 / Fig. 14 / Table 3 style).

  tools/scaling.py run CASE.yaml --ranks 1,2 [--repeat 3] [--set key=value ...] [--out runs/scaling]
  tools/scaling.py slurm CASE.yaml --ranks 1,2,4,8,16 [--time 02:00:00] [--partition P] [--out D]
        writes D/scaling_P.sbatch per rank count and D/submit.sh (sbatch each); then `report`
  tools/scaling.py report --out D [--png FILE]

The time of a run is its loop_seconds (the time-step loop, as LAMMPS' Loop time: set-up and the
final output not counted); with --repeat the median, repeats alternating over the rank counts.
Speed-up is relative to the smallest rank count P0: S(P) = P0 T(P0) / T(P), efficiency S(P) / P.
Each run's per-phase times are the mean over its ranks, and the busiest rank's (summary.json's
timers, per_rank). TESSERA names the binary (default build/bin/tessera).
"""
import argparse
import glob
import json
import os
import shlex
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TESSERA = os.environ.get("TESSERA", os.path.join(ROOT, "build", "bin", "tessera"))
PHASES = [("contact computation", ["contact_forces", "wall_forces"]), ("integration", ["integrate"]),
          ("cell search", ["neighbor"]), ("communication", ["ghost_comm", "migration"]),
          ("waiting", ["reduction"]), ("flow", ["flow", "advect", "viscous", "project"]), ("output", ["output"])]


def tessera_args(case, sets, out):
    args = ["run", os.path.abspath(case), "--quiet", "--output", out, "--set", "output.snapshot_interval=0"]
    for s in sets:
        args += ["--set", s]
    return args


def run(a):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    for rep in range(a.repeat):
        for p in a.ranks:
            out = os.path.join(a.out, f"P{p}_r{rep}")
            if os.path.exists(os.path.join(out, "summary.json")):
                continue
            cmd = ["mpirun", "-n", str(p), TESSERA] + tessera_args(a.case, a.set, out)
            print(" ".join(shlex.quote(c) for c in cmd), flush=True)
            subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
    report(a)


def slurm(a):
    os.makedirs(a.out, exist_ok=True)
    scripts = []
    for p in a.ranks:
        out = os.path.abspath(os.path.join(a.out, f"P{p}_r0"))
        line = " ".join(shlex.quote(x) for x in tessera_args(a.case, a.set, out))
        path = os.path.join(a.out, f"scaling_{p}.sbatch")
        partition = f"#SBATCH --partition={a.partition}\n" if a.partition else ""
        with open(path, "w") as f:
            f.write(f"""#!/bin/bash
#SBATCH --job-name=scaling-{p}
#SBATCH --ntasks={p}
#SBATCH --time={a.time}
{partition}#SBATCH --output={os.path.abspath(a.out)}/slurm-{p}-%j.out
# tools/scaling.py slurm: one run of {a.case} on {p} ranks; afterwards tools/scaling.py report --out {a.out}
cd {ROOT}
srun {TESSERA} {line}
""")
        scripts.append(path)
    with open(os.path.join(a.out, "submit.sh"), "w") as f:
        f.write("#!/bin/bash\n" + "".join(f"sbatch {s}\n" for s in scripts))
    os.chmod(os.path.join(a.out, "submit.sh"), 0o755)
    print(f"scaling: {len(scripts)} job scripts in {a.out}; submit with {os.path.join(a.out, 'submit.sh')}")


def load(out):
    runs = {}
    for path in sorted(glob.glob(os.path.join(out, "P*_r*", "summary.json"))):
        s = json.load(open(path))
        runs.setdefault(s["ranks"], []).append(s)
    return runs


def phase_times(s):
    t = s["timers"]
    mean, busiest = {}, {}
    for name, keys in PHASES:
        present = [k for k in keys if k in t]
        if not present:
            continue
        per_rank = [sum(t[k].get("per_rank", [t[k]["avg"]] * s["ranks"])[r] for k in present) for r in range(s["ranks"])]
        mean[name] = sum(per_rank) / len(per_rank)
        busiest[name] = max(per_rank)
    return mean, busiest


def report(a):
    runs = load(a.out)
    if not runs:
        sys.exit(f"scaling: no finished runs in {a.out}")
    ps = sorted(runs)
    times = {p: statistics.median(s["loop_seconds"] for s in runs[p]) for p in ps}
    spread = {p: (min(s["loop_seconds"] for s in runs[p]), max(s["loop_seconds"] for s in runs[p])) for p in ps}
    p0 = ps[0]
    print(f"| ranks | grid | loop time, median (min-max) | speed-up | efficiency | imbalance | runs |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for p in ps:
        s = runs[p][0]
        speedup = p0 * times[p0] / times[p]
        rows.append((p, speedup, speedup / p))
        grid = "x".join(str(g) for g in s.get("process_grid", []))
        imb = s.get("imbalance")
        print(f"| {p} | {grid} | {times[p]:.2f} s ({spread[p][0]:.2f}-{spread[p][1]:.2f}) | {speedup:.2f} | "
              f"{speedup / p:.2f} | {'-' if imb is None else f'{imb:.3f}'} | {len(runs[p])} |")
    print("\nper phase, mean over the ranks / busiest rank (s), first run of each rank count:")
    names = [n for n, _ in PHASES]
    print("| ranks | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for p in ps:
        mean, busiest = phase_times(runs[p][0])
        print(f"| {p} | " + " | ".join(f"{mean[n]:.2f} / {busiest[n]:.2f}" if n in mean else "-" for n in names) + " |")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 3, figsize=(13, 4))
        ax[0].plot(ps, [r[1] for r in rows], "o-", label="measured")
        ax[0].plot(ps, [p / p0 for p in ps], "k--", label="ideal")
        ax[0].set_xlabel("ranks"), ax[0].set_ylabel(f"speed-up (against {p0} rank{'s' if p0 > 1 else ''})")
        ax[0].legend()
        ax[1].plot(ps, [r[2] * p0 for r in rows], "o-")
        ax[1].set_ylim(0, 1.1), ax[1].set_xlabel("ranks"), ax[1].set_ylabel("parallel efficiency")
        bottom = [0.0] * len(ps)
        for n in names:
            v = [phase_times(runs[p][0])[0].get(n, 0.0) for p in ps]
            if any(v):
                ax[2].bar([str(p) for p in ps], v, bottom=bottom, label=n)
                bottom = [b + x for b, x in zip(bottom, v)]
        ax[2].set_xlabel("ranks"), ax[2].set_ylabel("seconds per rank (mean)"), ax[2].legend(fontsize=7)
        fig.suptitle(os.path.basename(runs[p0][0].get("case", {}).get("scene", "")) + f" scaling ({a.out})")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)
        print(f"wrote {a.png}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="mode", required=True)
    for mode in ("run", "slurm"):
        p = sub.add_parser(mode)
        p.add_argument("case")
        p.add_argument("--ranks", type=lambda s: [int(x) for x in s.split(",")], required=True)
        p.add_argument("--set", action="append", default=[])
        p.add_argument("--out", default="runs/scaling")
        p.add_argument("--png")
        if mode == "run":
            p.add_argument("--repeat", type=int, default=1)
        else:
            p.add_argument("--time", default="02:00:00")
            p.add_argument("--partition")
    p = sub.add_parser("report")
    p.add_argument("--out", default="runs/scaling")
    p.add_argument("--png")
    a = ap.parse_args()
    {"run": run, "slurm": slurm, "report": report}[a.mode](a)


if __name__ == "__main__":
    main()
