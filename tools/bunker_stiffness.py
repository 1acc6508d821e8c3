#!/usr/bin/python3
"""Speed against error of the bunker shot (issue 5): how far can the contact stiffness be lowered
(and dt raised with it, dt = t_contact / steps_per_contact) before the release angle and speed move
by more than 2 % from the stiffest run?

For each k_n (tangential 2/7 of it, every pair alike): the bed and ball of --bed (at rest at the
shot case's stiffness) relaxed 10 ms at k_n with restitution 0.1 (the resting overlaps change with
k_n), then the shot of --case at k_n. Prints and writes the table (k_n, dt, steps, wall time,
release angle and speed, their change from the stiffest run, upward impulse), and a plot.

usage: tools/bunker_stiffness.py [--case cases/bunker_shot/small.yaml]
         [--relax cases/bunker_shot/relax_small.yaml] [--bed runs/bunker_relax/checkpoint.h5]
         [--stiffness 1e6,3e6,1e7,3e7,1e8,3e8] [--ranks 2] [--out runs/bunker_stiffness] [--set K=V ...]
Output: OUT/stiffness.csv, OUT/stiffness.md, OUT/stiffness.png
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TESSERA = os.path.join(ROOT, "build", "bin", "tessera")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OMP_NUM_THREADS="1")


def with_stiffness(text, kn, restitution=None):
    """The case text with every pair's normal and tangential stiffness set to kn and 2/7 kn."""
    text = re.sub(r"normal_stiffness: [0-9.eE+-]+", "normal_stiffness: %g" % kn, text)
    text = re.sub(r"tangential_stiffness: [0-9.eE+-]+", "tangential_stiffness: %g" % (2.0 / 7.0 * kn), text)
    if restitution is not None:
        text = re.sub(r"restitution: [0-9.]+", "restitution: %g" % restitution, text)
    return text


def run(cmd, log):
    with open(log, "w") as f:
        r = subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        sys.exit("bunker stiffness: %s failed, see %s" % (" ".join(cmd), log))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="cases/bunker_shot/small.yaml")
    ap.add_argument("--relax", default="cases/bunker_shot/relax_small.yaml")
    ap.add_argument("--bed", default="runs/bunker_relax/checkpoint.h5")
    ap.add_argument("--stiffness", default="1e6,3e6,1e7,3e7,1e8,3e8")
    ap.add_argument("--relax-time", default="10 ms")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--out", default="runs/bunker_stiffness")
    ap.add_argument("--set", action="append", default=[])
    args = ap.parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    bed = os.path.abspath(args.bed)
    case_text, relax_text = open(args.case).read(), open(args.relax).read()
    mpi = ["mpirun", "-np", str(args.ranks), TESSERA, "run"]
    rows = []
    for kn in [float(v) for v in args.stiffness.split(",")]:
        tag = "k%g" % kn
        relax_case = os.path.join(out, tag + "_relax.yaml")
        shot_case = os.path.join(out, tag + "_shot.yaml")
        open(relax_case, "w").write(with_stiffness(relax_text, kn, restitution=0.1))
        open(shot_case, "w").write(with_stiffness(case_text, kn))
        relax_dir, shot_dir = os.path.join(out, tag + "_relax"), os.path.join(out, tag + "_shot")
        if not os.path.isfile(os.path.join(shot_dir, "summary.json")):
            run(mpi + [relax_case, "--output", relax_dir, "--quiet", "--set", "bed.file=" + bed,
                       "--set", "run.end_time=" + args.relax_time], relax_dir + ".log")
            run(mpi + [shot_case, "--output", shot_dir, "--quiet",
                       "--set", "bed.file=" + os.path.join(relax_dir, "checkpoint.h5")] +
                sum((["--set", s] for s in args.set), []), shot_dir + ".log")
        s = json.load(open(os.path.join(shot_dir, "summary.json")))
        q = s["quantities"]
        rows.append({"kn": kn, "dt": s["dt"], "steps": s["steps"], "wall_s": s["wall_seconds"],
                     "release_angle_deg": q["release_angle_deg"], "release_speed_mps": q["release_speed_mps"],
                     "club_upward_impulse": q["club_upward_impulse"],
                     "club_angular_velocity_loss": q["club_angular_velocity_loss"]})
        print("k_n %-8g dt %.3g s  %7d steps  %6.1f s  release %.2f deg %.3f m/s" % (
            kn, s["dt"], s["steps"], s["wall_seconds"], q["release_angle_deg"], q["release_speed_mps"]), flush=True)
    ref = max(rows, key=lambda r: r["kn"])
    for r in rows:
        r["angle_change"] = r["release_angle_deg"] / ref["release_angle_deg"] - 1
        r["speed_change"] = r["release_speed_mps"] / ref["release_speed_mps"] - 1
        r["within_2pct"] = abs(r["angle_change"]) <= 0.02 and abs(r["speed_change"]) <= 0.02
    keys = list(rows[0].keys())
    with open(os.path.join(out, "stiffness.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    md = ["| k_n (N/m) | dt (s) | steps | wall (s) | release angle (deg) | change | release speed (m/s) | change |"
          " upward impulse | within 2 % |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: r["kn"]):
        md.append("| %g | %.3g | %d | %.1f | %.2f | %+.1f %% | %.3f | %+.1f %% | %.3f | %s |" % (
            r["kn"], r["dt"], r["steps"], r["wall_s"], r["release_angle_deg"], 100 * r["angle_change"],
            r["release_speed_mps"], 100 * r["speed_change"], r["club_upward_impulse"],
            "yes" if r["within_2pct"] else "no"))
    open(os.path.join(out, "stiffness.md"), "w").write("\n".join(md) + "\n")
    print("\n".join(md))
    ok = [r for r in rows if r["within_2pct"]]
    # The fastest setting within 2 % whose stiffer neighbours are all within 2 % too.
    ordered = sorted(rows, key=lambda r: -r["kn"])
    fastest = None
    for r in ordered:
        if not r["within_2pct"]:
            break
        fastest = r
    if fastest:
        print("fastest within 2 %% of k_n = %g: k_n = %g (%.1f s against %.1f s)" % (
            ref["kn"], fastest["kn"], fastest["wall_s"], ref["wall_s"]))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rs = sorted(rows, key=lambda r: r["kn"])
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.6))
    k = [r["kn"] for r in rs]
    ax[0].semilogx(k, [100 * r["angle_change"] for r in rs], "o-", label="release angle")
    ax[0].semilogx(k, [100 * r["speed_change"] for r in rs], "s-", label="release speed")
    ax[0].axhspan(-2, 2, color="g", alpha=0.12, label="within 2 %")
    ax[0].set_xlabel("contact stiffness k_n (N/m)")
    ax[0].set_ylabel("change from the stiffest run (%)")
    ax[0].legend(fontsize=8)
    ax[0].grid(alpha=0.3)
    ax[1].loglog(k, [r["wall_s"] for r in rs], "o-")
    ax[1].set_xlabel("contact stiffness k_n (N/m)")
    ax[1].set_ylabel("wall time of the shot (s)")
    ax[1].grid(alpha=0.3, which="both")
    fig.suptitle("Bunker shot, small: speed against error", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "stiffness.png"), dpi=120)
    print("bunker stiffness: %s/stiffness.{csv,md,png}" % out)
    return 0 if ok else 1


if __name__ == "__main__":
    main()
