#!/usr/bin/env python3
"""Stokes flow through a simple cubic array of fixed spheres against Zick & Homsy (1982), Table 2.

    tools/sphere_array.py --c 0.216 --cells 8,12 [--ranks 2] [--out runs/sphere_array] [--set KEY=VALUE ...]
    tools/sphere_array.py RUN_DIR [RUN_DIR ...]          the measures of finished runs

Runs cases/coupled/sphere_array.yaml with spheres of solid fraction c (the 12 x 24 mesh scaled so
that its volume is c s^3: the case's 0.312585 mm semi-axis is 1.00777 times the radius of c = 0.125)
on n x n x 16n cells per spacing, and measures what tests/verification/test_sphere_array.cpp does:
the mean drag of the four middle spheres (their force less the buoyancy, from the last particle
snapshot) against F = 6 pi mu a K U, U the flux out of the bottom over the cross-section, and the
column's momentum balance sum F_z / (-rho g (s^2 H - V_b)).
"""
import argparse
import glob
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
K_ZICK_HOMSY = {0.064: 2.810, 0.125: 4.292, 0.216: 7.442, 0.343: 15.4}
RHO, MU, G, S, H = 1000.0, 1.0, 9.81, 1e-3, 16e-3


def measure(run):
    import h5py
    q = json.load(open(os.path.join(run, "summary.json")))
    quantities = q["quantities"]
    body_volume = quantities["body_volume"]
    c = body_volume / 8 / S**3
    flux = quantities["boundary_flux"]["z_low"]
    last = sorted(glob.glob(os.path.join(run, "snapshots", "particles_*.h5")))[-1]
    with h5py.File(last, "r") as h:
        z = h["position"][:, 2]
        fz = h["external_force"][:, 2]
    forces = [f for _, f in sorted(zip(z, fz))]
    buoyancy = RHO * G * body_volume / 8
    drag = sum(buoyancy - f for f in forces[2:6]) / 4
    a = (3 * c / (4 * math.pi)) ** (1 / 3) * S
    u = flux / S**2
    k = min(K_ZICK_HOMSY, key=lambda key: abs(key - c))
    carried = -RHO * G * (S * S * H - body_volume)
    leak = q.get("coupling", {}).get("leak_number", [float("nan")] * 2)
    return {"run": run, "c": c, "U": u, "K": drag / (6 * math.pi * MU * a * u), "K_ZH": K_ZICK_HOMSY[k],
            "error": drag / (6 * math.pi * MU * a * K_ZICK_HOMSY[k] * u) - 1,
            "balance": sum(forces) / carried, "leak": leak, "wall": q.get("wall_seconds", float("nan"))}


def run_case(c, cells, ranks, out, sets):
    text = open(os.path.join(ROOT, "cases", "coupled", "sphere_array.yaml")).read()
    a = (3 * c / (4 * math.pi)) ** (1 / 3) * S * 0.312585 / 0.310175
    text = text.replace("0.312585 mm", "%.9g" % a)
    os.makedirs(out, exist_ok=True)
    case = os.path.join(out, "case.yaml")
    open(case, "w").write(text)
    exe = os.environ.get("TESSERA", os.path.join(ROOT, "build", "bin", "tessera"))
    cmd = ["mpirun", "-n", str(ranks), exe, "run", case, "--output", out, "--quiet",
           "--set", "fluid.cells=[%d,%d,%d]" % (cells, cells, 16 * cells),
           "--set", "output.snapshot_interval=0.5 ms", "--set", "output.progress_interval=1000 s"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True)
    return measure(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*")
    ap.add_argument("--c", type=float, default=0.216)
    ap.add_argument("--cells", default="8,12")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--out", default="runs/sphere_array")
    ap.add_argument("--set", action="append", default=[], dest="sets")
    args = ap.parse_args()
    rows = [measure(r) for r in args.runs]
    if not args.runs:
        for n in (int(v) for v in args.cells.split(",")):
            rows.append(run_case(args.c, n, args.ranks, os.path.join(args.out, "c%g_n%d" % (args.c, n)), args.sets))
    print("%-40s %7s %11s %7s %7s %9s %9s %19s %8s" % ("run", "c", "U (m/s)", "K", "K_ZH", "error", "balance",
                                                       "leak number", "wall (s)"))
    for r in rows:
        print("%-40s %7.4f %11.4e %7.3f %7.3f %+8.2f%% %9.5f %9.2e-%8.2e %8.1f" % (
            r["run"][-40:], r["c"], r["U"], r["K"], r["K_ZH"], 100 * r["error"], r["balance"], r["leak"][0],
            r["leak"][1], r["wall"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
