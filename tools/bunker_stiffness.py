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
         [--ensemble N]
Output: OUT/stiffness.csv, OUT/stiffness.md, OUT/stiffness.png (means of the ensemble, +- their
standard error).
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "bench"))
from benchlib import ENV, ROOT, TESSERA  # noqa: E402


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
    ap.add_argument("--ensemble", type=int, default=1,
                    help="shots per stiffness: the depth moved by 0, +0.05, -0.05, +0.1, ... mm (a granular "
                         "shot is chaotic: one shot's result scatters by more than 2 %%)")
    args = ap.parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    bed = os.path.abspath(args.bed)
    case_text, relax_text = open(args.case).read(), open(args.relax).read()
    depth = float(re.search(r"shot_depth: ([0-9.eE+-]+) mm", case_text).group(1)) * 1e-3
    mpi = ["mpirun", "-np", str(args.ranks), TESSERA, "run"]
    rows = []
    for kn in [float(v) for v in args.stiffness.split(",")]:
        tag = "k%g" % kn
        relax_case = os.path.join(out, tag + "_relax.yaml")
        shot_case = os.path.join(out, tag + "_shot.yaml")
        open(relax_case, "w").write(with_stiffness(relax_text, kn, restitution=0.1))
        open(shot_case, "w").write(with_stiffness(case_text, kn))
        relax_dir = os.path.join(out, tag + "_relax")
        if not os.path.isfile(os.path.join(relax_dir, "checkpoint.h5")):
            run(mpi + [relax_case, "--output", relax_dir, "--quiet", "--set", "bed.file=" + bed,
                       "--set", "run.end_time=" + args.relax_time], relax_dir + ".log")
        shots = []
        for m in range(args.ensemble):
            offset = 0.05e-3 * ((m + 1) // 2) * (1 if m % 2 else -1)
            shot_dir = os.path.join(out, tag + "_shot" + ("" if m == 0 else "_e%d" % m))
            if not os.path.isfile(os.path.join(shot_dir, "summary.json")):
                run(mpi + [shot_case, "--output", shot_dir, "--quiet",
                           "--set", "bed.file=" + os.path.join(relax_dir, "checkpoint.h5")] +
                    (["--set", "club.shot_depth=%g" % (depth + offset)] if m else []) +
                    sum((["--set", s] for s in args.set), []), shot_dir + ".log")
            shots.append(json.load(open(os.path.join(shot_dir, "summary.json"))))
        s = shots[0]

        def stat(key):
            v = [x["quantities"][key] for x in shots]
            mean = sum(v) / len(v)
            sd = (sum((a - mean) ** 2 for a in v) / (len(v) - 1)) ** 0.5 if len(v) > 1 else 0.0
            return mean, sd / len(v) ** 0.5, sd
        angle, speed, impulse = stat("release_angle_deg"), stat("release_speed_mps"), stat("club_upward_impulse")
        rows.append({"kn": kn, "dt": s["dt"], "steps": s["steps"], "wall_s": s["wall_seconds"], "shots": len(shots),
                     "release_angle_deg": angle[0], "angle_stderr": angle[1], "angle_sd": angle[2],
                     "release_speed_mps": speed[0], "speed_stderr": speed[1], "speed_sd": speed[2],
                     "club_upward_impulse": impulse[0]})
        print("k_n %-8g dt %.3g s  %7d steps  %6.1f s  release %.2f +- %.2f deg %.3f +- %.3f m/s (%d shots)" % (
            kn, s["dt"], s["steps"], s["wall_seconds"], angle[0], angle[1], speed[0], speed[1], len(shots)),
            flush=True)
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
    md = ["| k_n (N/m) | dt (s) | steps | wall per shot (s) | shots | release angle (deg) | change |"
          " release speed (m/s) | change | upward impulse | within 2 % |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: r["kn"]):
        md.append("| %g | %.3g | %d | %.1f | %d | %.2f +- %.2f | %+.1f %% | %.3f +- %.3f | %+.1f %% | %.3f | %s |" % (
            r["kn"], r["dt"], r["steps"], r["wall_s"], r["shots"], r["release_angle_deg"], r["angle_stderr"],
            100 * r["angle_change"], r["release_speed_mps"], r["speed_stderr"], 100 * r["speed_change"],
            r["club_upward_impulse"], "yes" if r["within_2pct"] else "no"))
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
    ref_a, ref_s = ref["release_angle_deg"], ref["release_speed_mps"]
    ax[0].errorbar(k, [100 * r["angle_change"] for r in rs], yerr=[100 * r["angle_stderr"] / ref_a for r in rs],
                   fmt="o-", capsize=3, label="release angle")
    ax[0].errorbar(k, [100 * r["speed_change"] for r in rs], yerr=[100 * r["speed_stderr"] / ref_s for r in rs],
                   fmt="s-", capsize=3, label="release speed")
    ax[0].set_xscale("log")
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
