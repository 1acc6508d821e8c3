#!/usr/bin/python3
"""Bunker-shot parameter sweep (issue 5; the seed's Table 2) as independent batch jobs, then the
seed's table and figures.

The design variables are the case keys club.bounce_deg, club.loft_deg and club.shot_depth. The
seed's figures need two slices of Table 2, not its full product:
  Fig. 8  the club's upward impulse against the bounce angle (7, 10, 13 deg) at --loft and --depth;
  Fig. 9  release angle and speed over loft (56, 58, 60, 65 deg) x depth (0 to 10 mm) at --bounce;
  Fig. 7  the ball's velocity against time (the reference shot: --bounce, --loft, depth 0).
`--full` runs all 60 combinations instead.
`--ensemble N` runs N shots at the reference point (--loft, --bounce, depth 0) and at the slices'
corners (lofts 56 and 65 at depths 0 and 10 mm, bounces 7 and 13): shot m is m x --perturbation
deeper (2 um: a granular shot is chaotic, one shot scatters by about 4 % in speed). The table gives
each point's mean, its standard error and one shot's standard deviation; the figures their error
bars (two standard errors).

  tools/bunker_sweep.py run    [--case C] [--out D] [--jobs J] [--ranks R] [--full] [--set K=V ...]
      runs every job not yet completed in D (a job = one shot, D/<name>/summary.json), J at a time
      with R MPI ranks each, then writes the report;
  tools/bunker_sweep.py slurm  [same options] [--partition P] [--time HH:MM:SS]
      writes D/jobs.txt (one tessera command per line) and D/sweep.sbatch, a Slurm job array with
      one task per line (sbatch D/sweep.sbatch), then `report` gathers the results;
  tools/bunker_sweep.py report [--out D]
      D/release_table.csv and .md, D/fig7_ball_velocity.png, D/fig8_upward_impulse.png,
      D/fig9_release.png (contours of release angle and speed over loft and depth).

Every shot is stamped with the bed it started from (`bed`: the first 16 hex digits of a SHA-256
of the bed checkpoint's bodies and contact springs). `--prior CSV` (repeatable) takes the shots of
an earlier release_shots.csv (another allocation, another machine, a committed table) as done and
into the report, if they started from the same bed; shots from another bed are left out, with a
warning. A sweep can so be finished in pieces, even on a new machine that rebuilds the bed with the
same pipeline and build.
"""
import argparse
import csv
import itertools
import json
import os
import re
import shlex
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "bench"))
from benchlib import ENV, ROOT, TESSERA  # noqa: E402
BOUNCE = [7, 10, 13]
LOFT = [56, 58, 60, 65]
DEPTH_MM = [0, 2.5, 5, 7.5, 10]


def job_name(bounce, loft, depth, member=0):
    return "b%g_l%g_d%g" % (bounce, loft, depth) + ("_m%d" % member if member else "")


NAME = re.compile(r"^b([0-9.]+)_l([0-9.]+)_d([0-9.]+)(?:_m([0-9]+))?$")


def ensemble_points(args):
    """The points that get --ensemble shots: the reference point and the corners of both slices."""
    points = {(args.bounce, args.loft, 0.0)}
    points |= {(args.bounce, l, d) for l in (LOFT[0], LOFT[-1]) for d in (DEPTH_MM[0], DEPTH_MM[-1])}
    points |= {(b, args.loft, args.depth) for b in (BOUNCE[0], BOUNCE[-1])}
    return points


def jobs(args):
    if args.full:
        combos = list(itertools.product(BOUNCE, LOFT, DEPTH_MM))
    else:
        combos = [(b, args.loft, args.depth) for b in BOUNCE]
        combos += [(args.bounce, l, d) for l in LOFT for d in DEPTH_MM]
    seen, out = set(), []
    for c in combos:
        if c not in seen:
            seen.add(c)
            out.append(c + (0,))
    ens = ensemble_points(args)
    out += [c[:3] + (m,) for c in out if tuple(float(x) for x in c[:3]) in ens for m in range(1, args.ensemble)]
    return out


def command(args, combo, ranks):
    b, l, d, m = combo
    out = os.path.join(args.out, job_name(b, l, d, m))
    cmd = ["mpirun", "-np", str(ranks), TESSERA, "run", args.case, "--output", out, "--quiet",
           "--set", "club.bounce_deg=%g" % b, "--set", "club.loft_deg=%g" % l,
           "--set", "club.shot_depth=%.9g" % (d / 1000 + m * args.perturbation)]
    for s in args.set:
        cmd += ["--set", s]
    return cmd, out


def bed_file(args):
    """The case's bed checkpoint (bed.file, relative to the case's directory; --set bed.file=...)."""
    path = None
    for kv in args.set:
        if kv.startswith("bed.file="):
            return kv.split("=", 1)[1]
    text = open(os.path.join(ROOT, args.case)).read()
    m = re.search(r"^bed:\s*\n(?:\s+#.*\n)*\s+file:\s*([^\s#]+)", text, re.M)
    if m:
        path = os.path.normpath(os.path.join(os.path.dirname(os.path.join(ROOT, args.case)), m.group(1)))
    return path


def bed_digest(args):
    """The bed's identity: SHA-256 of its bodies and contact springs, 16 hex digits ('' if unknown)."""
    path = bed_file(args)
    if not path or not os.path.isfile(path):
        return ""
    import hashlib
    import h5py
    h = hashlib.sha256()
    with h5py.File(path, "r") as f:
        for name in ("bodies", "pair_history", "pair_keys"):
            if name in f:
                h.update(f[name][()].tobytes())
    return h.hexdigest()[:16]


def prior_rows(args, bed):
    """The shots of --prior CSVs that started from this bed."""
    rows = []
    for path in args.prior:
        kept = other = 0
        with open(path) as f:
            for r in csv.DictReader(f):
                if r.get("bed", "") != bed:
                    other += 1
                    continue
                row = {k: float(r[k]) for k in ["bounce_deg", "loft_deg", "depth_mm"] + QUANTITIES + ["wall_s"]}
                row.update(member=int(r["member"]), ball_hit_wall=r["ball_hit_wall"] == "True", bed=bed, dir=None)
                row["name"] = job_name(row["bounce_deg"], row["loft_deg"], row["depth_mm"], row["member"])
                rows.append(row)
                kept += 1
        print("bunker sweep: %s: %d shot(s) from this bed%s" % (
            path, kept, ", %d from another bed left out" % other if other else ""))
    return rows


def done(out):
    try:
        return json.load(open(os.path.join(out, "summary.json")))["status"] == "completed"
    except (OSError, ValueError, KeyError):
        return False


def run_local(args):
    os.makedirs(args.out, exist_ok=True)
    earlier = {r["name"] for r in prior_rows(args, bed_digest(args))}
    pending = [c for c in jobs(args) if job_name(*c) not in earlier and not done(command(args, c, args.ranks)[1])]
    print("bunker sweep: %d jobs, %d to run, %d at a time on %d rank(s) each" %
          (len(jobs(args)), len(pending), args.jobs, args.ranks))

    def one(combo):
        cmd, out = command(args, combo, args.ranks)
        os.makedirs(out, exist_ok=True)
        with open(out + ".log", "w") as f:
            r = subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=f, stderr=subprocess.STDOUT)
        status = "ok" if r.returncode == 0 else "FAILED (see %s.log)" % out
        print("  %s: %s" % (job_name(*combo), status), flush=True)
        return r.returncode

    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        failed = sum(1 for rc in pool.map(one, pending) if rc != 0)
    report(args)
    if failed:
        sys.exit("bunker sweep: %d job(s) failed" % failed)


def write_slurm(args):
    os.makedirs(args.out, exist_ok=True)
    earlier = {r["name"] for r in prior_rows(args, bed_digest(args))}
    lines = [" ".join(shlex.quote(x) for x in command(args, c, args.ranks)[0][4:]) for c in jobs(args)
             if job_name(*c) not in earlier]
    with open(os.path.join(args.out, "jobs.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")
    script = """#!/bin/bash
#SBATCH --job-name=bunker-sweep
#SBATCH --array=1-{n}
#SBATCH --ntasks={ranks}
#SBATCH --time={time}
{partition}#SBATCH --output={out}/slurm-%A_%a.out
# One bunker shot per array task (tools/bunker_sweep.py slurm); afterwards:
#   tools/bunker_sweep.py report --out {out}
cd {root}
line=$(sed -n "${{SLURM_ARRAY_TASK_ID}}p" {out}/jobs.txt)
eval srun {tessera} $line
""".format(n=len(lines), ranks=args.ranks, time=args.time, out=os.path.abspath(args.out), root=ROOT,
           tessera=TESSERA, partition="#SBATCH --partition=%s\n" % args.partition if args.partition else "")
    path = os.path.join(args.out, "sweep.sbatch")
    with open(path, "w") as f:
        f.write(script)
    print("bunker sweep: %d jobs in %s; submit with: sbatch %s" % (len(lines), os.path.join(args.out, "jobs.txt"),
                                                                    path))


def load(out, bed=""):
    """One row per completed shot; `member` is its place in its point's ensemble."""
    rows = []
    for name in sorted(os.listdir(out)):
        path = os.path.join(out, name, "summary.json")
        match = NAME.match(name)
        if not match or not os.path.isfile(path):
            continue
        s = json.load(open(path))
        if s.get("status") != "completed":
            continue
        q = s["quantities"]
        rows.append({"name": name, "bounce_deg": float(match.group(1)), "loft_deg": float(match.group(2)),
                     "depth_mm": float(match.group(3)), "member": int(match.group(4) or 0),
                     "release_angle_deg": q["release_angle_deg"],
                     "release_speed_mps": q["release_speed_mps"], "release_time_s": q["release_time"],
                     "club_upward_impulse": q["club_upward_impulse"],
                     "club_angular_velocity_loss": q["club_angular_velocity_loss"],
                     "ball_hit_wall": q.get("ball_hit_wall", False), "wall_s": s["wall_seconds"],
                     "bed": bed, "dir": os.path.join(out, name)})
    return rows


QUANTITIES = ["release_angle_deg", "release_speed_mps", "release_time_s", "club_upward_impulse",
              "club_angular_velocity_loss"]


def points(rows):
    """Each design point's ensemble: the mean, its standard error and one shot's standard deviation
    of every quantity (0 for a single shot), the shot count and the median wall time."""
    groups = {}
    for r in rows:
        groups.setdefault((r["bounce_deg"], r["loft_deg"], r["depth_mm"]), []).append(r)
    out = []
    for (b, l, d), shots in sorted(groups.items()):
        p = {"bounce_deg": b, "loft_deg": l, "depth_mm": d, "shots": len(shots),
             "wall_s": statistics.median(r["wall_s"] for r in shots),
             "ball_hit_wall": sum(1 for r in shots if r["ball_hit_wall"]),
             "members": shots,
             # the first shot whose ball.csv is here (a --prior shot has only its row)
             "traced": min((r for r in shots if r["dir"]), key=lambda r: r["member"], default=None)}
        for k in QUANTITIES:
            v = [r[k] for r in shots]
            sd = statistics.stdev(v) if len(v) > 1 else 0.0
            p[k], p[k + "_sd"], p[k + "_stderr"] = statistics.fmean(v), sd, sd / len(v) ** 0.5
        out.append(p)
    return out


def report(args):
    bed = bed_digest(args)
    rows = load(args.out, bed) if os.path.isdir(args.out) else []
    here = {r["name"] for r in rows}
    rows += [r for r in prior_rows(args, bed) if r["name"] not in here]
    if not rows:
        sys.exit("bunker sweep: no completed runs in %s" % args.out)
    os.makedirs(args.out, exist_ok=True)
    keys = ["bounce_deg", "loft_deg", "depth_mm", "member"] + QUANTITIES + ["ball_hit_wall", "wall_s", "bed"]
    with open(os.path.join(args.out, "release_shots.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(sorted(rows, key=lambda r: (r["bounce_deg"], r["loft_deg"], r["depth_mm"], r["member"])))
    pts = points(rows)
    keys = ["bounce_deg", "loft_deg", "depth_mm", "shots"] + [k + s for k in QUANTITIES for s in ("", "_stderr", "_sd")]
    keys += ["ball_hit_wall", "wall_s"]
    with open(os.path.join(args.out, "release_table.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(pts)

    def pm(p, k, fmt):
        return (fmt + " +- " + fmt) % (p[k], p[k + "_stderr"]) if p["shots"] > 1 else fmt % p[k]
    with open(os.path.join(args.out, "release_table.md"), "w") as f:
        f.write("| bounce | loft | depth mm | shots | release angle deg | release speed m/s | speed sd (one shot) |"
                " upward impulse | club loses rad/s | wall s |\n|---|---|---|---|---|---|---|---|---|---|\n")
        for p in pts:
            f.write("| %g | %g | %g | %d | %s | %s | %s | %s | %s | %.0f |\n" % (
                p["bounce_deg"], p["loft_deg"], p["depth_mm"], p["shots"], pm(p, "release_angle_deg", "%.1f"),
                pm(p, "release_speed_mps", "%.2f"), "%.2f" % p["release_speed_mps_sd"] if p["shots"] > 1 else "",
                pm(p, "club_upward_impulse", "%.3f"), pm(p, "club_angular_velocity_loss", "%.1f"), p["wall_s"]))
        f.write("\n+- : one standard error of the ensemble's mean (shot m is m x %g um deeper).\n" %
                (1e6 * args.perturbation))
    print(open(os.path.join(args.out, "release_table.md")).read())
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def trace(r):
        t, v = [], []
        with open(os.path.join(r["dir"], "ball.csv")) as f:
            for row in csv.DictReader(f):
                t.append(1e3 * float(row["time"]))
                v.append((float(row["ball_vx"]) ** 2 + float(row["ball_vz"]) ** 2) ** 0.5)
        return t, v
    # Fig. 7: the ball's speed against time in the reference shots, every ensemble member (thin).
    ref = [p for p in pts if p["depth_mm"] == 0 and p["bounce_deg"] == args.bounce and p["traced"]]
    if ref:
        fig, ax = plt.subplots(figsize=(5.5, 3.8))
        for p in sorted(ref, key=lambda p: p["loft_deg"]):
            line, = ax.plot(*trace(p["traced"]), label="loft %g deg%s" % (
                p["loft_deg"], " (%d shots)" % p["shots"] if p["shots"] > 1 else ""))
            for r in p["members"]:
                if r is not p["traced"] and r["dir"]:
                    ax.plot(*trace(r), color=line.get_color(), lw=0.5, alpha=0.5)
            ax.errorbar([1e3 * p["release_time_s"]], [p["release_speed_mps"]],
                        xerr=[2e3 * p["release_time_s_stderr"]], yerr=[2 * p["release_speed_mps_stderr"]],
                        color=line.get_color(), fmt="o", ms=3, capsize=3)
        ax.set_xlabel("time (ms)")
        ax.set_ylabel("ball speed (m/s)")
        ax.set_title("Ball speed (bounce %g deg, depth 0); dots: mean release +- 2 s.e." % args.bounce, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "fig7_ball_velocity.png"), dpi=120)
        plt.close(fig)
    # Fig. 8: upward impulse against bounce.
    sel = sorted([p for p in pts if p["loft_deg"] == args.loft and p["depth_mm"] == args.depth],
                 key=lambda p: p["bounce_deg"])
    if sel:
        fig, ax = plt.subplots(figsize=(4.5, 3.5))
        ax.errorbar([p["bounce_deg"] for p in sel], [p["club_upward_impulse"] for p in sel],
                    yerr=[2 * p["club_upward_impulse_stderr"] for p in sel], fmt="o-", capsize=3)
        ax.set_xlabel("bounce angle (deg)")
        ax.set_ylabel("upward impulse / (m_club omega_0 L)")
        ax.set_title("Club upward impulse (loft %g, depth %g mm; +- 2 s.e.)" % (args.loft, args.depth), fontsize=9)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "fig8_upward_impulse.png"), dpi=120)
        plt.close(fig)
    # Fig. 9: release angle and speed over loft x depth: contours of the means, then against depth
    # per loft with error bars.
    grid = [p for p in pts if p["bounce_deg"] == args.bounce]
    lofts = sorted({p["loft_deg"] for p in grid})
    depths = sorted({p["depth_mm"] for p in grid})
    if len(lofts) > 1 and len(depths) > 1:
        at = {(p["loft_deg"], p["depth_mm"]): p for p in grid}
        if all((l, d) in at for l in lofts for d in depths):
            fig, axes = plt.subplots(2, 2, figsize=(9, 7.2))
            for col, (key, label) in enumerate((("release_angle_deg", "release angle (deg)"),
                                                ("release_speed_mps", "release speed (m/s)"))):
                ax = axes[0][col]
                z = [[at[(l, d)][key] for l in lofts] for d in depths]
                cs = ax.contourf(lofts, depths, z, levels=12, cmap="viridis")
                ax.contour(lofts, depths, z, levels=12, colors="k", linewidths=0.3)
                fig.colorbar(cs, ax=ax, label=label)
                ax.plot([l for l in lofts for d in depths], [d for l in lofts for d in depths], "k.", ms=3)
                ax.set_xlabel("loft angle (deg)")
                ax.set_ylabel("shot depth below the reference (mm)")
                ax.invert_yaxis()
                ax = axes[1][col]
                for l in lofts:
                    ax.errorbar(depths, [at[(l, d)][key] for d in depths],
                                yerr=[2 * at[(l, d)][key + "_stderr"] for d in depths], fmt="o-", ms=3, capsize=3,
                                label="loft %g" % l)
                ax.set_xlabel("shot depth below the reference (mm)")
                ax.set_ylabel(label)
                ax.grid(alpha=0.3)
                ax.legend(fontsize=7)
            fig.suptitle("Release angle and speed (bounce %g deg; means, error bars +- 2 s.e. where an "
                         "ensemble ran)" % args.bounce, fontsize=10)
            fig.tight_layout()
            fig.savefig(os.path.join(args.out, "fig9_release.png"), dpi=120)
            plt.close(fig)
    print("bunker sweep: report in %s (release_table.csv/.md, release_shots.csv, fig7/8/9 PNGs)" % args.out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["run", "slurm", "report"])
    ap.add_argument("--case", default="cases/bunker_shot/small.yaml")
    ap.add_argument("--out", default="runs/bunker_sweep")
    ap.add_argument("--jobs", type=int, default=1, help="jobs at a time (run)")
    ap.add_argument("--ranks", type=int, default=2, help="MPI ranks per job")
    ap.add_argument("--full", action="store_true", help="all 60 combinations of Table 2")
    ap.add_argument("--bounce", type=float, default=10, help="the bounce of the loft x depth slice (Fig. 9)")
    ap.add_argument("--loft", type=float, default=58, help="the loft of the bounce slice (Fig. 8)")
    ap.add_argument("--depth", type=float, default=0, help="the depth (mm) of the bounce slice (Fig. 8)")
    ap.add_argument("--set", action="append", default=[], help="another case override for every job")
    ap.add_argument("--ensemble", type=int, default=1, help="shots at the reference point and the corners")
    ap.add_argument("--perturbation", type=float, default=2e-6, help="depth step between ensemble members (m)")
    ap.add_argument("--prior", action="append", default=[],
                    help="release_shots.csv of earlier shots from the same bed: done, and in the report")
    ap.add_argument("--partition", default="")
    ap.add_argument("--time", default="00:30:00")
    args = ap.parse_args()
    if args.mode == "run":
        run_local(args)
    elif args.mode == "slurm":
        write_slurm(args)
    else:
        report(args)


if __name__ == "__main__":
    main()
