#!/usr/bin/python3
"""The bunker shot's open choices against the seed's calibration point (issue 20).

The seed leaves the club's drive open: its mass and moment of inertia per unit depth, the swing
moment Mo of eq. 8, where the swing starts; and the contact stiffness (the 2D disc thickness t acts
as the stiffness does: every mass, the club's included, scales with t while k_n does not, and
scaling every mass and k_n together leaves the motion unchanged, so t x s is k_n / s:
tools/bunker_stiffness.py measures it). One entry of the seed's Table 3 is known (issue 20): loft
58, bounce 10, depth 0 released the ball at 52.5 deg and 15.9 m/s.

  tools/bunker_calibrate.py sensitivity [--case C] [--ensemble N] [--out D] [--ranks R] [--set K=V]
      (docs/validation.md's table: --set club.applied_moment_per_depth=0, the free swing the study
      started from; the cases now carry the calibrated Mo)
      the reference shot (loft 58, bounce 10, depth 0) with each open choice moved in turn
      (VARIATIONS below), N shots each (shot m m x 2 um deeper: one shot scatters by about 4 % in
      speed): each setting's mean release angle and speed +- their standard errors and the change
      from the case's own setting. Writes D/sensitivity.csv, .md and .png.
  tools/bunker_calibrate.py scan --parameter KEY --values a,b,c [--target-speed 15.9] [same options]
      N shots at each value of one parameter (KEY a case key; the club's mass is scanned as
      `club.mass_scale`, which multiplies mass_per_depth and moment_of_inertia_per_depth together);
      fits the mean release speed in the value (least squares weighted by the means' standard
      errors: a line for 2-3 values, a parabola for 4 or more, since the speed curves upwards once
      the club gains speed) and prints the value that reaches --target-speed, the standard error
      of that value (the fit's covariance, to first order), and the angle the same kind of fit
      predicts there. D/scan_<KEY>.csv, .md and .png.
  tools/bunker_calibrate.py scan --parameter KEY --values a,b,c --reference b [same options]
      a convergence study instead of a calibration (e.g. KEY solid.steps_per_contact): each value's
      means and medians, their relative change from the reference value's ensemble +- the change's
      standard error, and the verdict of tools/bunker_stiffness.py (within 2 %: "yes" by two
      standard errors, "no" outside by two, else "likely" / "unlikely"); no fit.
      D/converge_<KEY>.csv, .md and .png.
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
from bunker_stiffness import ensemble_stats, verdict  # noqa: E402

TARGET_ANGLE, TARGET_SPEED = 52.5, 15.9  # the seed's Table 3 at loft 58, bounce 10, depth 0 (issue 20)


def case_value(text, key):
    m = re.search(r"^\s*%s:\s*([0-9.eE+-]+)" % re.escape(key), text, re.M)
    if not m:
        sys.exit("bunker calibrate: %s not in the case" % key)
    return float(m.group(1))


def variations(case_text):
    """(label, overrides) of the sensitivity study: each open choice moved alone."""
    m, i = case_value(case_text, "mass_per_depth"), case_value(case_text, "moment_of_inertia_per_depth")
    club = lambda s: ["club.mass_per_depth=%g" % (s * m), "club.moment_of_inertia_per_depth=%g" % (s * i)]
    return [
        ("case (mass %g kg/m, I %g kg m, Mo as given, clearance 2 mm)" % (m, i), []),
        ("club mass and inertia x 0.5", club(0.5)),
        ("club mass and inertia x 2", club(2.0)),
        ("club mass and inertia x 4", club(4.0)),
        ("Mo = 1000 N m/m (a golfer's ~75 N m over 75 mm)", ["club.applied_moment_per_depth=1000"]),
        ("Mo = 5000 N m/m", ["club.applied_moment_per_depth=5000"]),
        ("swing starts 10 mm above the bed (not 2)", ["club.start_clearance=0.01"]),
        ("club-sand friction 0.1 (not 0.2)", ["@friction:club,sand=0.1"]),
        # Not open in the seed (Table 1 gives the ball's friction with sand, 0.2), but candidates for
        # the release angle, which none of the above moves.
        ("ball-sand friction 0.4 (not 0.2)", ["@friction:ball,sand=0.4"]),
        ("club-ball friction 0.05 (not 0.2)", ["@friction:club,ball=0.05"]),
        ("club sole camber 3 mm (not 1)", ["club.sole_camber=0.003"]),
    ]


def shot_case(case_text, overrides, out, tag):
    """The case with the overrides that --set cannot express (a pair's friction in a list) applied to
    its text; returns the case path and the remaining --set overrides."""
    text, sets = case_text, []
    for o in overrides:
        m = re.match(r"@friction:(\w+),(\w+)=(.*)", o)
        if m:
            pat = r"(\{materials: \[%s, %s\],[^}]*friction: )[0-9.]+" % (m.group(1), m.group(2))
            text, n = re.subn(pat, r"\g<1>" + m.group(3), text)
            if n != 1:
                sys.exit("bunker calibrate: no pair %s, %s in the case" % (m.group(1), m.group(2)))
        else:
            sets.append(o)
    path = os.path.join(out, tag + ".yaml")
    open(path, "w").write(text)
    return path, sets


def free_flight_angle(out):
    """The ball's direction (deg) at the first ball.csv sample after its last contact: a second
    reading of the release (the seed does not define its moment), against the scene's largest speed."""
    import math
    rows = list(csv.DictReader(open(os.path.join(out, "ball.csv"))))
    touching = [i for i, r in enumerate(rows) if float(r["ball_contact_fx"]) or float(r["ball_contact_fz"])]
    if not touching or touching[-1] + 1 >= len(rows):
        return None  # still in contact at the end
    r = rows[touching[-1] + 1]
    return math.degrees(math.atan2(float(r["ball_vz"]), float(r["ball_vx"])))


def ensemble(args, case_path, sets, tag):
    """args.ensemble shots of the reference point, shot m m x perturbation deeper; their summaries."""
    case_text = open(case_path).read()
    depth = float(re.search(r"shot_depth: ([0-9.eE+-]+) mm", case_text).group(1)) * 1e-3
    shots = []
    for k in range(args.ensemble):
        out = os.path.join(args.out, tag + "_m%d" % k)
        summary = os.path.join(out, "summary.json")
        if not os.path.isfile(summary):
            cmd = ["mpirun", "-np", str(args.ranks), TESSERA, "run", case_path, "--output", out, "--quiet",
                   "--set", "bed.file=" + os.path.abspath(args.bed),
                   "--set", "club.shot_depth=%.9g" % (depth + k * args.perturbation)]
            for s in args.set + sets:  # the variation last: it wins
                cmd += ["--set", s]
            with open(out + ".log", "w") as f:
                if subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=f, stderr=subprocess.STDOUT).returncode:
                    sys.exit("bunker calibrate: %s failed, see %s.log" % (" ".join(cmd), out))
        shots.append(json.load(open(summary)))
    q = lambda key: ensemble_stats([s["quantities"][key] for s in shots])
    free = [free_flight_angle(os.path.join(args.out, tag + "_m%d" % k)) for k in range(args.ensemble)]
    free = [a for a in free if a is not None]
    return {"angle": q("release_angle_deg"), "speed": q("release_speed_mps"),
            "loss": q("club_angular_velocity_loss"), "impulse": q("club_upward_impulse"),
            "angle_free": ensemble_stats(free) if free else None, "free_shots": len(free),
            "shots": len(shots), "wall_s": sorted(s["wall_seconds"] for s in shots)[len(shots) // 2]}


def fmt(st, f):
    return (f + " +- " + f) % (st["mean"], st["mean_stderr"])


def sensitivity(args):
    case_text = open(args.case).read()
    rows = []
    for n, (label, overrides) in enumerate(variations(case_text)):
        path, sets = shot_case(case_text, overrides, args.out, "v%d" % n)
        r = ensemble(args, path, sets, "v%d" % n)
        r["label"], r["overrides"] = label, " ".join(overrides)
        rows.append(r)
        print("%-55s angle %s deg  speed %s m/s  club loses %s rad/s  (%d shots, %.0f s each)" % (
            label, fmt(r["angle"], "%.2f"), fmt(r["speed"], "%.3f"), fmt(r["loss"], "%.1f"), r["shots"],
            r["wall_s"]), flush=True)
    base = rows[0]
    md = ["| setting | release angle (deg) | change | release speed (m/s) | change | speed sd (one shot) |"
          " club loses (rad/s) | upward impulse |", "|---" * 8 + "|"]
    for r in rows:
        for q in ("angle", "speed"):
            d = r[q]["mean"] - base[q]["mean"]
            e = (r[q]["mean_stderr"] ** 2 + base[q]["mean_stderr"] ** 2) ** 0.5 if r is not base else 0.0
            r[q + "_change"], r[q + "_change_stderr"] = d, e
        md.append("| %s | %s | %s | %s | %s | %.2f | %s | %s |" % (
            r["label"], fmt(r["angle"], "%.2f"), "" if r is base else "%+.2f +- %.2f" % (
                r["angle_change"], r["angle_change_stderr"]),
            fmt(r["speed"], "%.3f"), "" if r is base else "%+.2f +- %.2f" % (r["speed_change"], r["speed_change_stderr"]),
            r["speed"]["sd"], fmt(r["loss"], "%.1f"), fmt(r["impulse"], "%.3f")))
    md.append("")
    md.append("%d shots per setting (shot m m x %g um deeper); +- one standard error; the seed's point: %.1f deg, "
              "%.1f m/s." % (args.ensemble, 1e6 * args.perturbation, TARGET_ANGLE, TARGET_SPEED))
    open(os.path.join(args.out, "sensitivity.md"), "w").write("\n".join(md) + "\n")
    with open(os.path.join(args.out, "sensitivity.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["setting", "overrides", "shots", "angle_mean", "angle_stderr", "speed_mean", "speed_stderr",
                    "speed_sd", "club_loss_mean", "upward_impulse_mean", "wall_s"])
        for r in rows:
            w.writerow([r["label"], r["overrides"], r["shots"], r["angle"]["mean"], r["angle"]["mean_stderr"],
                        r["speed"]["mean"], r["speed"]["mean_stderr"], r["speed"]["sd"], r["loss"]["mean"],
                        r["impulse"]["mean"], r["wall_s"]])
    print("\n".join(md))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for r in rows:
        ax.errorbar(r["speed"]["mean"], r["angle"]["mean"], xerr=2 * r["speed"]["mean_stderr"],
                    yerr=2 * r["angle"]["mean_stderr"], fmt="o", capsize=3, label=r["label"])
    ax.plot([TARGET_SPEED], [TARGET_ANGLE], "k*", ms=14, label="seed (Table 3)")
    ax.set_xlabel("release speed (m/s)")
    ax.set_ylabel("release angle (deg)")
    ax.set_title("Reference shot (loft 58, bounce 10, depth 0): each open choice moved alone;\n"
                 "means +- 2 s.e. of %d shots" % args.ensemble, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6.5)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "sensitivity.png"), dpi=120)


def finish_axes(ax, xlabel, ylabel):
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def fit(x, y, err):
    """Weighted least squares polynomial (degree 1 for up to 3 points, 2 from 4): coefficients,
    highest power first, and their covariance (from the standard errors, not rescaled)."""
    import numpy as np
    deg = 1 if len(x) < 4 else 2
    c, cov = np.polyfit(np.array(x, float), np.array(y, float), deg, w=1 / np.array(err, float), cov="unscaled")
    return c, cov


def solve(c, cov, target, lo, hi):
    """The value in [lo, hi] (or nearest to it) where the fit reaches target, and its standard error
    by the delta method (dv/dc_k = -v^k / p'(v))."""
    import numpy as np
    roots = [r.real for r in np.roots(np.array(c) - np.eye(len(c))[-1] * target) if abs(r.imag) < 1e-12]
    if not roots:
        sys.exit("bunker calibrate: the fit never reaches the target")
    v = min(roots, key=lambda r: 0 if lo <= r <= hi else min(abs(r - lo), abs(r - hi)))
    deg = len(c) - 1
    slope = np.polyval(np.polyder(c), v)
    grad = np.array([-v ** (deg - k) / slope for k in range(deg + 1)])
    return v, float(np.sqrt(grad @ cov @ grad))


def scan(args):
    case_text = open(args.case).read()
    values = [float(v) for v in args.values.split(",")]
    key = args.parameter
    rows = []
    for v in values:
        tag = "scan_%s_%g" % (key.replace(".", "_"), v)
        if key == "club.mass_scale":
            m, i = case_value(case_text, "mass_per_depth"), case_value(case_text, "moment_of_inertia_per_depth")
            overrides = ["club.mass_per_depth=%g" % (v * m), "club.moment_of_inertia_per_depth=%g" % (v * i)]
        else:
            overrides = ["%s=%g" % (key, v)]
        path, sets = shot_case(case_text, overrides, args.out, tag)
        r = ensemble(args, path, sets, tag)
        r["value"] = v
        rows.append(r)
        print("%s = %-8g angle %s deg  speed %s m/s  club loses %s rad/s (%d shots); free-flight angle %s deg "
              "(%d shots)" % (key, v, fmt(r["angle"], "%.2f"), fmt(r["speed"], "%.3f"), fmt(r["loss"], "%.1f"),
                              r["shots"], fmt(r["angle_free"], "%.2f") if r["angle_free"] else "-", r["free_shots"]),
              flush=True)
    if args.reference is not None:
        return converge(args, rows)
    import numpy as np
    x = [r["value"] for r in rows]
    fits = {q: fit(x, [r[q]["mean"] for r in rows], [r[q]["mean_stderr"] for r in rows]) for q in ("speed", "angle")}
    value, value_err = solve(*fits["speed"], args.target_speed, min(x), max(x))
    angle_there = float(np.polyval(fits["angle"][0], value))
    form = "parabola" if len(fits["speed"][0]) == 3 else "line"
    tag = key.replace(".", "_")
    with open(os.path.join(args.out, "scan_%s.csv" % tag), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([key, "shots", "angle_mean", "angle_stderr", "speed_mean", "speed_stderr", "speed_sd",
                    "club_loss_mean", "upward_impulse_mean"])
        for r in rows:
            w.writerow([r["value"], r["shots"], r["angle"]["mean"], r["angle"]["mean_stderr"], r["speed"]["mean"],
                        r["speed"]["mean_stderr"], r["speed"]["sd"], r["loss"]["mean"], r["impulse"]["mean"]])
    md = ["| %s | shots | release angle (deg) | release speed (m/s) | club loses (rad/s) |" % key, "|---" * 5 + "|"]
    md += ["| %g | %d | %s | %s | %s |" % (r["value"], r["shots"], fmt(r["angle"], "%.2f"), fmt(r["speed"], "%.3f"),
                                           fmt(r["loss"], "%.1f")) for r in rows]
    md.append("")
    md.append("Weighted least-squares %s through the mean speeds (coefficients, highest power first: %s): the "
              "target %.2f m/s at %s = %.4g +- %.2g; the angle's %s predicts %.2f deg there (the seed: %.1f)." % (
                  form, ", ".join("%.4g" % v for v in fits["speed"][0]), args.target_speed, key, value, value_err,
                  form, angle_there, TARGET_ANGLE))
    open(os.path.join(args.out, "scan_%s.md" % tag), "w").write("\n".join(md) + "\n")
    print("\n".join(md))
    print("calibrated: %s = %.4g +- %.2g" % (key, value, value_err))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, q, target, label in ((axes[0], "speed", args.target_speed, "release speed (m/s)"),
                                 (axes[1], "angle", TARGET_ANGLE, "release angle (deg)")):
        ax.errorbar(x, [r[q]["mean"] for r in rows], yerr=[2 * r[q]["mean_stderr"] for r in rows], fmt="o",
                    capsize=3, label="mean +- 2 s.e. (%d shots)" % args.ensemble)
        xs = np.linspace(min(x + [value]), max(x + [value]), 100)
        ax.plot(xs, np.polyval(fits[q][0], xs), "-", lw=0.8, label="weighted %s" % form)
        ax.axhline(target, color="k", ls=":", lw=0.8, label="seed (Table 3)")
        ax.axvline(value, color="r", ls="--", lw=0.8, label="calibrated")
        finish_axes(ax, key, label)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "scan_%s.png" % tag), dpi=120)

def relative_change(r, base, q, stat):
    """(change, its standard error) of r's mean or median of q relative to base's."""
    a, b = r[q][stat], base[q][stat]
    ea, eb = r[q][stat + "_stderr"], base[q][stat + "_stderr"]
    if r is base:
        return 0.0, 0.0
    return a / b - 1.0, ((ea / b) ** 2 + (a * eb / b ** 2) ** 2) ** 0.5


def converge(args, rows):
    """The scan's ensembles against the --reference value's: relative changes and verdicts."""
    key = args.parameter
    base = [r for r in rows if r["value"] == args.reference]
    if not base:
        sys.exit("bunker calibrate: --reference %g is not among --values" % args.reference)
    base = base[0]
    md = ["| %s | shots | wall per shot (s) | angle, mean (deg) | change | speed, mean (m/s) | change | within 2 %% "
          "(means) | angle, median | change | speed, median | change | within 2 %% (medians) | club loses (rad/s) |"
          % key, "|---" * 14 + "|"]
    out = []
    for r in rows:
        cells, verdicts = {}, {}
        for stat in ("mean", "median"):
            worst = []
            for q in ("angle", "speed"):
                c, e = relative_change(r, base, q, stat)
                cells[q, stat] = "" if r is base else "%+.1f +- %.1f %%" % (100 * c, 100 * e)
                worst.append(verdict(c, e))
            order = ["yes", "likely", "unlikely", "no"]
            verdicts[stat] = "reference" if r is base else max(worst, key=order.index)
        f2 = lambda q, stat: "%.2f +- %.2f" % (r[q][stat], r[q][stat + "_stderr"])
        f3 = lambda q, stat: "%.3f +- %.3f" % (r[q][stat], r[q][stat + "_stderr"])
        md.append("| %g | %d | %.1f | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            r["value"], r["shots"], r["wall_s"], f2("angle", "mean"), cells["angle", "mean"], f3("speed", "mean"),
            cells["speed", "mean"], verdicts["mean"], f2("angle", "median"), cells["angle", "median"],
            f3("speed", "median"), cells["speed", "median"], verdicts["median"], fmt(r["loss"], "%.1f")))
        out.append([r["value"], r["shots"], r["wall_s"], r["angle"]["mean"], r["angle"]["mean_stderr"],
                    r["speed"]["mean"], r["speed"]["mean_stderr"], r["angle"]["median"], r["angle"]["median_stderr"],
                    r["speed"]["median"], r["speed"]["median_stderr"], r["speed"]["sd"], r["loss"]["mean"],
                    verdicts["mean"], verdicts["median"]])
    md.append("")
    md.append("%d shots per value (shot m m x %g um deeper); +- one standard error (the median's by a bootstrap); "
              "changes relative to %s = %g." % (args.ensemble, 1e6 * args.perturbation, key, args.reference))
    tag = key.replace(".", "_")
    open(os.path.join(args.out, "converge_%s.md" % tag), "w").write("\n".join(md) + "\n")
    with open(os.path.join(args.out, "converge_%s.csv" % tag), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([key, "shots", "wall_s", "angle_mean", "angle_stderr", "speed_mean", "speed_stderr",
                    "angle_median", "angle_median_stderr", "speed_median", "speed_median_stderr", "speed_sd",
                    "club_loss_mean", "verdict_means", "verdict_medians"])
        w.writerows(out)
    print("\n".join(md))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    x = [r["value"] for r in rows]
    for ax, q, label in ((axes[0], "speed", "release speed (m/s)"), (axes[1], "angle", "release angle (deg)")):
        for stat, fmt_, dx in (("mean", "o", -0.02), ("median", "s", 0.02)):
            ax.errorbar([v * (1 + dx) for v in x], [r[q][stat] for r in rows],
                        yerr=[2 * r[q][stat + "_stderr"] for r in rows], fmt=fmt_, capsize=3,
                        label="%s +- 2 s.e. (%d shots)" % (stat, args.ensemble))
        b = base[q]["median"]
        ax.axhspan(0.98 * b, 1.02 * b, color="0.85", label="reference median +- 2 %")
        ax.set_xscale("log")
        finish_axes(ax, key, label)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "converge_%s.png" % tag), dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["sensitivity", "scan"])
    ap.add_argument("--case", default="cases/bunker_shot/small.yaml")
    ap.add_argument("--bed", default="runs/bunker_relax/checkpoint.h5")
    ap.add_argument("--out", default="runs/bunker_calibrate")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--ensemble", type=int, default=8)
    ap.add_argument("--perturbation", type=float, default=2e-6)
    ap.add_argument("--parameter", default="club.mass_scale")
    ap.add_argument("--values", default="1,2,4")
    ap.add_argument("--target-speed", type=float, default=TARGET_SPEED)
    ap.add_argument("--reference", type=float, default=None,
                    help="a convergence study: changes from this value's ensemble, no fit")
    ap.add_argument("--set", action="append", default=[])
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    sensitivity(args) if args.mode == "sensitivity" else scan(args)


if __name__ == "__main__":
    main()
