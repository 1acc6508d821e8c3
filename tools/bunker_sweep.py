#!/usr/bin/python3
"""Bunker-shot parameter sweep (issue 5; the seed's Table 2) as independent batch jobs, then the
seed's table and figures.

The design variables are the case keys club.bounce_deg, club.loft_deg and club.shot_depth. The
seed's figures need two slices of Table 2, not its full product:
  Fig. 8  the club's upward impulse against the bounce angle (7, 10, 13 deg) at --loft and --depth;
  Fig. 9  release angle and speed over loft (56, 58, 60, 65 deg) x depth (0 to 10 mm) at --bounce;
  Fig. 7  the ball's velocity against time (the reference shot: --bounce, --loft, depth 0).
`--full` runs all 60 combinations instead.

  tools/bunker_sweep.py run    [--case C] [--out D] [--jobs J] [--ranks R] [--full] [--set K=V ...]
      runs every job not yet completed in D (a job = one shot, D/<name>/summary.json), J at a time
      with R MPI ranks each, then writes the report;
  tools/bunker_sweep.py slurm  [same options] [--partition P] [--time HH:MM:SS]
      writes D/jobs.txt (one tessera command per line) and D/sweep.sbatch, a Slurm job array with
      one task per line (sbatch D/sweep.sbatch), then `report` gathers the results;
  tools/bunker_sweep.py report [--out D]
      D/release_table.csv and .md, D/fig7_ball_velocity.png, D/fig8_upward_impulse.png,
      D/fig9_release.png (contours of release angle and speed over loft and depth).
"""
import argparse
import csv
import itertools
import json
import os
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "bench"))
from benchlib import ENV, ROOT, TESSERA  # noqa: E402
BOUNCE = [7, 10, 13]
LOFT = [56, 58, 60, 65]
DEPTH_MM = [0, 2.5, 5, 7.5, 10]


def job_name(bounce, loft, depth):
    return "b%g_l%g_d%g" % (bounce, loft, depth)


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
            out.append(c)
    return out


def command(args, combo, ranks):
    b, l, d = combo
    out = os.path.join(args.out, job_name(b, l, d))
    cmd = ["mpirun", "-np", str(ranks), TESSERA, "run", args.case, "--output", out, "--quiet",
           "--set", "club.bounce_deg=%g" % b, "--set", "club.loft_deg=%g" % l,
           "--set", "club.shot_depth=%g" % (d / 1000)]
    for s in args.set:
        cmd += ["--set", s]
    return cmd, out


def done(out):
    try:
        return json.load(open(os.path.join(out, "summary.json")))["status"] == "completed"
    except (OSError, ValueError, KeyError):
        return False


def run_local(args):
    os.makedirs(args.out, exist_ok=True)
    pending = [c for c in jobs(args) if not done(command(args, c, args.ranks)[1])]
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
    lines = [" ".join(shlex.quote(x) for x in command(args, c, args.ranks)[0][4:]) for c in jobs(args)]
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


def load(out):
    rows = []
    for name in sorted(os.listdir(out)):
        path = os.path.join(out, name, "summary.json")
        if not os.path.isfile(path):
            continue
        s = json.load(open(path))
        if s.get("status") != "completed":
            continue
        club = s["case"]["club"]
        q = s["quantities"]
        depth = club["shot_depth"]
        if isinstance(depth, str) and depth.strip().endswith("mm"):
            depth_mm = float(depth.strip()[:-2])
        else:
            depth_mm = round(1000 * float(str(depth).split()[0]), 6)
        rows.append({"name": name, "bounce_deg": float(club["bounce_deg"]), "loft_deg": float(club["loft_deg"]),
                     "depth_mm": depth_mm, "release_angle_deg": q["release_angle_deg"],
                     "release_speed_mps": q["release_speed_mps"], "release_time_s": q["release_time"],
                     "club_upward_impulse": q["club_upward_impulse"],
                     "club_angular_velocity_loss": q["club_angular_velocity_loss"],
                     "ball_hit_wall": q.get("ball_hit_wall", False), "wall_s": s["wall_seconds"],
                     "dir": os.path.join(out, name)})
    return rows


def report(args):
    rows = load(args.out)
    if not rows:
        sys.exit("bunker sweep: no completed runs in %s" % args.out)
    keys = ["bounce_deg", "loft_deg", "depth_mm", "release_angle_deg", "release_speed_mps", "release_time_s",
            "club_upward_impulse", "club_angular_velocity_loss", "ball_hit_wall", "wall_s"]
    with open(os.path.join(args.out, "release_table.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(args.out, "release_table.md"), "w") as f:
        f.write("| bounce | loft | depth mm | release angle deg | release speed m/s | upward impulse | club loses rad/s |"
                " wall s |\n|---|---|---|---|---|---|---|---|\n")
        for r in sorted(rows, key=lambda r: (r["bounce_deg"], r["loft_deg"], r["depth_mm"])):
            f.write("| %g | %g | %g | %.1f | %.2f | %.3f | %.1f | %.0f |\n" % (
                r["bounce_deg"], r["loft_deg"], r["depth_mm"], r["release_angle_deg"], r["release_speed_mps"],
                r["club_upward_impulse"], r["club_angular_velocity_loss"], r["wall_s"]))
    print(open(os.path.join(args.out, "release_table.md")).read())
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    # Fig. 7: the ball's velocity against time in the reference shot(s).
    ref = [r for r in rows if r["depth_mm"] == 0 and r["bounce_deg"] == args.bounce]
    if ref:
        fig, ax = plt.subplots(figsize=(5.5, 3.8))
        for r in sorted(ref, key=lambda r: r["loft_deg"]):
            t, vx, vz = [], [], []
            with open(os.path.join(r["dir"], "ball.csv")) as f:
                for row in csv.DictReader(f):
                    t.append(1e3 * float(row["time"]))
                    vx.append(float(row["ball_vx"]))
                    vz.append(float(row["ball_vz"]))
            ax.plot(t, [(a * a + b * b) ** 0.5 for a, b in zip(vx, vz)], label="loft %g deg" % r["loft_deg"])
            ax.axvline(1e3 * r["release_time_s"], color=ax.lines[-1].get_color(), lw=0.6, ls=":")
        ax.set_xlabel("time (ms)")
        ax.set_ylabel("ball speed (m/s)")
        ax.set_title("Ball speed (bounce %g deg, depth 0); dotted: release" % args.bounce, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "fig7_ball_velocity.png"), dpi=120)
        plt.close(fig)
    # Fig. 8: upward impulse against bounce.
    sel = sorted([r for r in rows if r["loft_deg"] == args.loft and r["depth_mm"] == args.depth],
                 key=lambda r: r["bounce_deg"])
    if sel:
        fig, ax = plt.subplots(figsize=(4.5, 3.5))
        ax.plot([r["bounce_deg"] for r in sel], [r["club_upward_impulse"] for r in sel], "o-")
        ax.set_xlabel("bounce angle (deg)")
        ax.set_ylabel("upward impulse / (m_club omega_0 L)")
        ax.set_title("Club upward impulse (loft %g, depth %g mm)" % (args.loft, args.depth), fontsize=9)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "fig8_upward_impulse.png"), dpi=120)
        plt.close(fig)
    # Fig. 9: release angle and speed over loft x depth.
    grid = [r for r in rows if r["bounce_deg"] == args.bounce]
    lofts = sorted({r["loft_deg"] for r in grid})
    depths = sorted({r["depth_mm"] for r in grid})
    if len(lofts) > 1 and len(depths) > 1:
        at = {(r["loft_deg"], r["depth_mm"]): r for r in grid}
        if all((l, d) in at for l in lofts for d in depths):
            fig, axes = plt.subplots(1, 2, figsize=(9, 3.8))
            for ax, key, label in ((axes[0], "release_angle_deg", "release angle (deg)"),
                                   (axes[1], "release_speed_mps", "release speed (m/s)")):
                z = [[at[(l, d)][key] for l in lofts] for d in depths]
                cs = ax.contourf(lofts, depths, z, levels=12, cmap="viridis")
                ax.contour(lofts, depths, z, levels=12, colors="k", linewidths=0.3)
                fig.colorbar(cs, ax=ax, label=label)
                ax.plot([l for l in lofts for d in depths], [d for l in lofts for d in depths], "k.", ms=3)
                ax.set_xlabel("loft angle (deg)")
                ax.set_ylabel("shot depth below the reference (mm)")
                ax.invert_yaxis()
            fig.suptitle("Release angle and speed (bounce %g deg)" % args.bounce, fontsize=10)
            fig.tight_layout()
            fig.savefig(os.path.join(args.out, "fig9_release.png"), dpi=120)
            plt.close(fig)
    print("bunker sweep: report in %s (release_table.csv/.md, fig7/8/9 PNGs)" % args.out)


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
