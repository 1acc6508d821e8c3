#!/usr/bin/python3
"""Grid study of a settling sphere against ten Cate et al. (2002, Phys. Fluids 14, 4012).

Runs cases/coupled/settling_sphere.yaml (case E3 by default; --case E1, E2 or E4) on 4.2 and 8.4
cells per diameter (--fine adds 16.8; --grids 4.2,8.4,12.6 names any), prints the sphere's largest
downward speed against the largest speed measured in the experiment's 160 mm box (their Table 2),
and with three grids or more the observed order of the last three (their own convergence, whatever
the ratios: u_i = u + C h_i^p solved for p) and the extrapolated speed; draws the speed against time
(--png). Reuses a run directory that already holds a finished series.csv.

--height H (m) makes the box H tall instead of the experiment's 0.16 m, the sphere starting 40 mm
below its top, and --end T runs to T seconds instead of the case's 0.8 s. In the experiment's box the
sphere is fastest at 1.0-1.1 s, two diameters above the floor (--end 1.6 runs to its landing); a
0.32 m box and 1.5 s give the terminal speed, 0.7 % above that largest speed.

  tools/settling_sphere.py --ranks 2 --grids 4.2,8.4,12.6 --end 1.6 --out runs/settling_box --png F
  tools/settling_sphere.py --ranks 2 --out runs/settling_tall --height 0.32 --end 1.5
"""
import argparse
import csv
import os
import subprocess
import sys

# Liquid density, viscosity; u_inf, the Reynolds number on it (ten Cate's Table 1: the unbounded
# terminal speed of Abraham's drag correlation, not a measurement: Abraham's C_D = 24 / 9.06^2
# (1 + 9.06 / Re^0.5)^2 gives 0.0383, 0.0599, 0.0906, 0.1284 m/s); and u_max / u_inf, the largest
# speed measured in the 160 mm box (their Table 2; the values waLBerla's SettlingSphereInBox
# benchmark also compares with).
CASES = {
    "E1": (970, 0.373, 0.038, 1.5, 0.947),
    "E2": (965, 0.212, 0.060, 4.1, 0.953),
    "E3": (962, 0.113, 0.091, 11.6, 0.959),
    "E4": (960, 0.058, 0.128, 31.9, 0.955),
}

def cells_for(per_d, height):
    """The grid for per_d cells per diameter (15 mm) over the 100 mm cross-section: 4.2 -> 28 x 28 x 44
    in the experiment's 160 mm box (nz = 11 nx / 7: cells about as tall as wide), nz scaled with the box."""
    nx = round(per_d * 100 / 15)
    return nx, round(nx * 11 / 7 * height / 0.16)


def observed_order(h, u):
    """p and the limit from three grids (h decreasing): (u1 - u2) / (u2 - u3) = (h1^p - h2^p) / (h2^p - h3^p),
    solved by bisection on p in [0.05, 8]; None when the differences change sign (not converging)."""
    d12, d23 = u[0] - u[1], u[1] - u[2]
    if d12 == 0 or d23 == 0 or (d12 > 0) != (d23 > 0):
        return None
    target = d12 / d23
    f = lambda p: (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - target
    lo, hi = 0.05, 8.0
    if f(lo) * f(hi) > 0:
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(lo) * f(mid) <= 0:
            hi = mid
        else:
            lo = mid
    p = 0.5 * (lo + hi)
    return p, u[2] - d23 / ((h[1] / h[2]) ** p - 1)


def series(path):
    with open(path) as f:
        rows = [r for r in csv.DictReader(f) if r.get("body_mean_vz")]
    return [float(r["time"]) for r in rows], [-float(r["body_mean_vz"]) for r in rows]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="E3", choices=sorted(CASES))
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--out", default="runs/settling")
    ap.add_argument("--fine", action="store_true", help="also 16.8 cells per diameter (about an hour on 2 cores)")
    ap.add_argument("--grids", help="cells per diameter, comma-separated (default 4.2,8.4; --fine adds 16.8)")
    ap.add_argument("--height", type=float, default=0.16, help="box height in m (the experiment's: 0.16)")
    ap.add_argument("--end", type=float, default=0.8, help="end time in s (the case's: 0.8)")
    ap.add_argument("--set", action="append", default=[], help="KEY=VALUE for every run (tessera run --set)")
    ap.add_argument("--png")
    a = ap.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    rho, mu, u_inf, reynolds, ratio = CASES[a.case]
    measured = ratio * u_inf
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    results = []
    grids = a.grids.split(",") if a.grids else ["4.2", "8.4"] + (["16.8"] if a.fine else [])
    for per_d in grids:
        out = os.path.join(a.out, f"{a.case}_{per_d}")
        nx, nz = cells_for(float(per_d), a.height)
        cells = f"[{nx},{nx},{nz}]"
        top = f"[0.05,0.05,{a.height}]"
        done = os.path.exists(os.path.join(out, "summary.json"))
        if not done:
            cmd = ["mpirun", "-n", str(a.ranks), os.environ.get("TESSERA", os.path.join(root, "build/bin/tessera")), "run",
                   os.path.join(root, "cases/coupled/settling_sphere.yaml"), "--output", out, "--quiet",
                   "--set", f"fluid.cells={cells}", "--set", f"fluid.liquid.density={rho}",
                   "--set", f"fluid.liquid.viscosity={mu} Pa*s", "--set", "output.snapshot_interval=0",
                   "--set", f"domain.box_max={top}", "--set", f"solid.walls.0.max={top}",
                   "--set", f"initial.liquid.0.box.max={top}", "--set", f"bodies.list.0.position=[0,0,{a.height - 0.04}]",
                   "--set", f"run.end_time={a.end}"] + [x for kv in a.set for x in ("--set", kv)]
            subprocess.run(cmd, check=True, env=env)
        t, v = series(os.path.join(out, "series.csv"))
        results.append((per_d, t, v, max(v)))
    print(f"ten Cate {a.case}: largest speed measured in the 160 mm box {measured:.4f} m/s ({ratio} u_inf; "
          f"u_inf {u_inf} m/s unbounded, Re {reynolds})")
    for per_d, _, _, u in results:
        print(f"  {per_d:>5} cells per diameter: {u:.4f} m/s, {100 * (u - measured) / measured:+.1f} % against the "
              f"measured largest speed")
    if len(results) >= 3:
        last = results[-3:]
        fit = observed_order([1 / float(r[0]) for r in last], [r[3] for r in last])
        names = ", ".join(r[0] for r in last)
        if fit is None:
            print(f"  {names} cells: not converging monotonically (no observed order)")
        else:
            p, limit = fit
            print(f"  {names} cells: observed order {p:.2f}, extrapolated {limit:.4f} m/s "
                  f"({100 * (limit - measured) / measured:+.1f} % against the measured largest speed)")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4))
        for per_d, t, v, _ in results:
            ax.plot(t, v, label=f"Tessera, {per_d} cells per diameter")
        ax.axhline(measured, color="k", ls="--", label=f"ten Cate et al. (2002) {a.case}, largest speed measured")
        ax.axhline(u_inf, color="gray", ls=":", label="unbounded (Abraham's correlation)")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("settling speed (m/s)")
        ax.set_title(f"Sphere settling in silicone oil, Re {reynolds}")
        ax.legend(loc="lower center", fontsize=9)
        fig.tight_layout()
        fig.savefig(a.png, dpi=120)
        print("figure:", a.png)


if __name__ == "__main__":
    sys.exit(main())
