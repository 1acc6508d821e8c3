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
         [--ensemble N] [--perturbation 2e-6]
Output: OUT/stiffness.csv, OUT/stiffness.md, OUT/stiffness.png: the ensemble's means and medians
+- their standard errors (the median's by bootstrap), and the count of fast shots (released more
than 15 % faster than the median: a second outcome, rare, that moves the means). A stiffness is
within 2 % ("yes") when both changes lie inside 2 % by two standard errors of the change, "no" when
either lies outside by two; otherwise "likely" (both estimates inside) or "unlikely". Verdicts for
the means and for the medians; the default to pick is the softest whose row and stiffer rows are
"yes" or "likely".
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


def ensemble_stats(v, resamples=2000):
    """Mean and median of an ensemble with their standard errors (the median's by a bootstrap with a
    fixed seed, so the table is reproducible), and one shot's standard deviation."""
    import random
    import statistics
    n = len(v)
    mean = sum(v) / n
    sd = statistics.stdev(v) if n > 1 else 0.0
    median = statistics.median(v)
    rng = random.Random(12345)
    boot = [statistics.median(rng.choices(v, k=n)) for _ in range(resamples)] if n > 1 else [median]
    return {"mean": mean, "mean_stderr": sd / n ** 0.5, "sd": sd, "median": median,
            "median_stderr": statistics.stdev(boot) if n > 1 else 0.0}


def verdict(change, err):
    """Two standard errors either side of the change: inside 2 % ("yes"), outside ("no"), or not
    resolved, the estimate inside ("likely") or outside ("unlikely")."""
    c = abs(change)
    return "yes" if c + 2 * err <= 0.02 else "no" if c - 2 * err > 0.02 else "likely" if c <= 0.02 else "unlikely"


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
                    help="shots per stiffness, shot m that much deeper: m * --perturbation (a granular shot is "
                         "chaotic: one shot's result scatters by more than 2 %%)")
    ap.add_argument("--perturbation", type=float, default=2e-6,
                    help="depth step between ensemble members (m), deeper only: a shallower shot moves the "
                         "club's edge into the ball, another regime (release speeds of 13-15 m/s at -0.6 to "
                         "-0.95 mm)")
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
            offset = m * args.perturbation
            shot_dir = os.path.join(out, tag + "_shot" + ("" if m == 0 else "_d%gum" % (1e6 * offset)))
            if not os.path.isfile(os.path.join(shot_dir, "summary.json")):
                run(mpi + [shot_case, "--output", shot_dir, "--quiet",
                           "--set", "bed.file=" + os.path.join(relax_dir, "checkpoint.h5")] +
                    (["--set", "club.shot_depth=%g" % (depth + offset)] if m else []) +
                    sum((["--set", s] for s in args.set), []), shot_dir + ".log")
            shots.append(json.load(open(os.path.join(shot_dir, "summary.json"))))
        s = shots[0]

        def stat(key):
            return ensemble_stats([x["quantities"][key] for x in shots])
        angle, speed = stat("release_angle_deg"), stat("release_speed_mps")
        impulse = stat("club_upward_impulse")
        speeds = [x["quantities"]["release_speed_mps"] for x in shots]
        row = {"kn": kn, "dt": s["dt"], "steps": s["steps"], "wall_s": s["wall_seconds"], "shots": len(shots)}
        for name, st in (("angle", angle), ("speed", speed)):
            row.update({name + "_mean": st["mean"], name + "_mean_stderr": st["mean_stderr"], name + "_sd": st["sd"],
                        name + "_median": st["median"], name + "_median_stderr": st["median_stderr"]})
        row["club_upward_impulse"] = impulse["mean"]
        # The fast tail: shots released more than 15 % faster than the ensemble's median, a rare second
        # outcome whose mechanism is not identified (docs/validation.md).
        row["fast_tail"] = sum(1 for v in speeds if v > 1.15 * speed["median"])
        rows.append(row)
        print("k_n %-8g dt %.3g s  %7d steps  %6.1f s  release mean %.2f +- %.2f deg %.3f +- %.3f m/s, median "
              "%.2f +- %.2f deg %.3f +- %.3f m/s (%d shots, %d fast)" % (
                  kn, s["dt"], s["steps"], s["wall_seconds"], angle["mean"], angle["mean_stderr"], speed["mean"],
                  speed["mean_stderr"], angle["median"], angle["median_stderr"], speed["median"],
                  speed["median_stderr"], len(shots), row["fast_tail"]), flush=True)
    ref = max(rows, key=lambda r: r["kn"])
    for r in rows:
        for centre in ("mean", "median"):
            verdicts = []
            for name in ("angle", "speed"):
                q, se = name + "_" + centre, name + "_" + centre + "_stderr"
                ratio = r[q] / ref[q]
                # Standard error of the ratio of two independent estimates (none for the reference itself).
                err = 0.0 if r is ref else ratio * ((r[se] / r[q]) ** 2 + (ref[se] / ref[q]) ** 2) ** 0.5
                r[q + "_change"], r[q + "_change_stderr"] = ratio - 1, err
                verdicts.append(verdict(ratio - 1, err))
            r["within_2pct_" + centre] = next(v for v in ("no", "unlikely", "likely", "yes") if v in verdicts)
    keys = list(rows[0].keys())
    with open(os.path.join(out, "stiffness.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    md = ["| k_n (N/m) | dt (s) | steps | wall per shot (s) | shots | angle, mean (deg) | change |"
          " speed, mean (m/s) | change | within 2 % (means) | angle, median (deg) | change | speed, median (m/s) |"
          " change | within 2 % (medians) | fast shots | upward impulse |", "|---" * 17 + "|"]
    for r in sorted(rows, key=lambda r: r["kn"]):
        cells = ["%g" % r["kn"], "%.3g" % r["dt"], "%d" % r["steps"], "%.1f" % r["wall_s"], "%d" % r["shots"]]
        for centre in ("mean", "median"):
            for name, fmt in (("angle", "%.2f +- %.2f"), ("speed", "%.3f +- %.3f")):
                q = name + "_" + centre
                cells += [fmt % (r[q], r[q + "_stderr"]),
                          "%+.1f +- %.1f %%" % (100 * r[q + "_change"], 100 * r[q + "_change_stderr"])]
            cells.append(r["within_2pct_" + centre])
        cells += ["%d" % r["fast_tail"], "%.3f" % r["club_upward_impulse"]]
        md.append("| " + " | ".join(cells) + " |")
    open(os.path.join(out, "stiffness.md"), "w").write("\n".join(md) + "\n")
    print("\n".join(md))
    print("within 2 %: yes / no when the change is inside / outside 2 % by two standard errors; likely / "
          "unlikely when it is not resolved and the estimate is inside / outside. Medians: standard errors by "
          "bootstrap. Fast shots: released more than 15 % faster than the ensemble's median.")
    # The fastest setting whose change, and every stiffer setting's, is inside 2 % (yes or likely).
    ordered = sorted(rows, key=lambda r: -r["kn"])
    fastest = {}
    for centre in ("mean", "median"):
        for r in ordered:
            if r["within_2pct_" + centre] not in ("yes", "likely"):
                break
            fastest[centre] = r
        if centre in fastest:
            f = fastest[centre]
            print("fastest within 2 %% of k_n = %g by the %ss: k_n = %g (%.1f s against %.1f s; %s)" % (
                ref["kn"], centre, f["kn"], f["wall_s"], ref["wall_s"], f["within_2pct_" + centre]))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rs = sorted(rows, key=lambda r: r["kn"])
    fig, ax = plt.subplots(1, 3, figsize=(12, 3.6))
    k = [r["kn"] for r in rs]
    # Error bars: two standard errors of the change (the reference's own scatter included).
    for a, name, title in ((ax[0], "angle", "release angle"), (ax[1], "speed", "release speed")):
        for centre, fmt, shift in (("mean", "o-", 1.0), ("median", "s--", 1.08)):
            q = name + "_" + centre
            a.errorbar([x * shift for x in k], [100 * r[q + "_change"] for r in rs],
                       yerr=[200 * r[q + "_change_stderr"] for r in rs], fmt=fmt, capsize=3,
                       mfc="none" if centre == "median" else None, label=centre)
        a.set_xscale("log")
        a.axhspan(-2, 2, color="g", alpha=0.12, label="within 2 %")
        a.set_xlabel("contact stiffness k_n (N/m)")
        a.set_ylabel("change from the stiffest run (%)")
        a.set_title(title, fontsize=9)
        a.legend(fontsize=8)
        a.grid(alpha=0.3)
    ax[2].loglog(k, [r["wall_s"] for r in rs], "o-")
    ax[2].set_xlabel("contact stiffness k_n (N/m)")
    ax[2].set_ylabel("wall time of one shot (s)")
    from matplotlib.ticker import ScalarFormatter, NullFormatter
    ax[2].yaxis.set_major_formatter(ScalarFormatter())
    ax[2].yaxis.set_minor_formatter(NullFormatter())
    ax[2].set_yticks([5, 10, 20, 50, 100, 200])
    ax[2].set_ylim(0.7 * min(r["wall_s"] for r in rs), 1.4 * max(r["wall_s"] for r in rs))
    ax[2].grid(alpha=0.3, which="both")
    fig.suptitle("Bunker shot, small: speed against error (%d shots per stiffness, bars: 2 standard errors)"
                 % min(r["shots"] for r in rs), fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "stiffness.png"), dpi=120)
    print("bunker stiffness: %s/stiffness.{csv,md,png}" % out)
    return 0 if fastest else 1


if __name__ == "__main__":
    main()
