#!/usr/bin/env python3
"""Creeping flow through a fixed packed bed against Carman-Kozeny (issue 15).

    tools/packed_bed.py RUN_DIR [RUN_DIR ...]            the measures of finished runs
    tools/packed_bed.py --study --out DIR [--cells 2,3,4.5,6] [--ranks 2]
                                                         prepares the bed, runs the grid study,
                                                         prints the table, draws DIR/packed_bed.png

A run is cases/coupled/packed_bed.yaml (grains held, liquid pulled down through the bed by gravity).
From the last field snapshot: the plane means of the pressure p(z) and of the solid fraction; in the
middle of the bed (the planes between a quarter and three quarters of its height, its top being the
highest plane whose mean solid fraction is half that of the bed's lowest quarter) the drag per unit bed volume

    f = dp/dz + rho g       (least squares over those planes; the liquid flows down, the drag on it
                            points up and carries its weight and the pressure's rise),

the porosity e = 1 - mean solid fraction there, the superficial velocity U = flux out of the bottom
over the cross-section, and Carman-Kozeny's f_CK = 180 mu U (1 - e)^2 / (e^3 d^2) with d = 6 V / S of
the grain's tetrahedral mesh (its volume and surface, as the flow sees it); Ergun's viscous term has
150 for 180. Reported: f / f_CK, the permeability k = mu U / f, and Re = rho U d / mu.
"""
import argparse
import glob
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def grain_volume_surface(run):
    """Volume and surface of one grain's mesh (the first grain of the last snapshot)."""
    import h5py
    last = sorted(glob.glob(os.path.join(run, "snapshots", "particles_*.h5")))[-1]
    with h5py.File(last, "r") as h:
        nodes = h["surface_nodes"][:]
        tris = h["surface_triangles"][:]
        ids = h["surface_id"][:].ravel()
    first = tris[ids == ids[0]]
    a, b, c = nodes[first[:, 0]], nodes[first[:, 1]], nodes[first[:, 2]]
    surface = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    volume = abs(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6  # closed surface, divergence theorem
    return volume, surface


def measure(run):
    import h5py
    s = json.load(open(os.path.join(run, "summary.json")))
    case = s["case"]
    fluid = case["fluid"]
    rho = float(fluid["liquid"]["density"])
    mu = float(str(fluid["liquid"]["viscosity"]).split()[0])
    g = abs(float(fluid["gravity"][2]))
    lo = [float(str(v).split()[0]) * (1e-3 if "mm" in str(v) else 1) for v in case["domain"]["box_min"]]
    hi = [float(str(v).split()[0]) * (1e-3 if "mm" in str(v) else 1) for v in case["domain"]["box_max"]]
    area = (hi[0] - lo[0]) * (hi[1] - lo[1])
    last = sorted(glob.glob(os.path.join(run, "fields", "fields_*.h5")))[-1]
    with h5py.File(last, "r") as h:
        p = h["pressure"][:]
        alpha = h["solid_fraction"][:]
        w = h["velocity"][:, :, :, 2]
    nz = p.shape[0]
    dz = (hi[2] - lo[2]) / nz
    z = lo[2] + (np.arange(nz) + 0.5) * dz
    pm = p.mean(axis=(1, 2))
    am = np.minimum(alpha, 1).mean(axis=(1, 2))
    middle = am[: max(1, nz // 4)].mean()
    top = z[np.nonzero(am >= 0.5 * middle)[0].max()]  # the highest plane still half as full
    sel = (z > 0.25 * top) & (z < 0.75 * top)
    slope = np.polyfit(z[sel], pm[sel], 1)[0]
    f = slope + rho * g  # the flow goes down (U > 0 out of the bottom): the drag on the liquid points up
    e = 1 - am[sel].mean()
    u = s["quantities"]["boundary_flux"]["z_low"] / area
    vg, sg = grain_volume_surface(run)
    d = 6 * vg / sg
    f_ck = 180 * mu * u * (1 - e) ** 2 / (e ** 3 * d * d)
    # The core: columns of cells more than one grain short axis from the side walls, where the bed
    # is not loosened by them; its own porosity and superficial velocity (the mean of the cells' w,
    # grains' cells included), the same pressure gradient.
    ny, nx = p.shape[1], p.shape[2]
    hx, hy = (hi[0] - lo[0]) / nx, (hi[1] - lo[1]) / ny
    cells = s["cells"]
    short = None
    for shape in case["solid"]["shapes"]:
        if "spheroid" in shape:
            axes = [float(str(v).split()[0]) * (1e-3 if "mm" in str(v) else 1) for v in shape["spheroid"]["semi_axes"]]
            short = 2 * min(axes)
    band = short or 0.0
    xc = (np.arange(nx) + 0.5) * hx
    yc = (np.arange(ny) + 0.5) * hy
    core = np.outer((yc > band) & (yc < hi[1] - lo[1] - band), (xc > band) & (xc < hi[0] - lo[0] - band))
    e_core = 1 - np.minimum(alpha, 1)[sel][:, core].mean()
    u_core = -w[sel][:, core].mean()
    f_ck_core = 180 * mu * u_core * (1 - e_core) ** 2 / (e_core ** 3 * d * d)
    return {
        "run": run, "cells": fluid["cells"], "cells_per_short_axis": short / dz if short else None,
        "bed_top": top, "porosity": e, "U": u, "drag_per_volume": f, "carman_kozeny": f_ck,
        "ratio_ck": f / f_ck, "core_porosity": e_core, "core_U": u_core, "core_ratio_ck": f / f_ck_core, "ratio_ergun": f / (f_ck * 150 / 180), "permeability": mu * u / f,
        "Re": rho * u * d / mu, "d_sv": d, "grain_volume": vg, "wall_seconds": s["wall_seconds"],
        "time": s["time"],
    }


def print_rows(rows):
    print("| cells | per short axis | bed top (mm) | porosity | U (mm/s) | Re | f (N/m^3) | Carman-Kozeny (N/m^3) "
          "| f / CK | f / Ergun | core: porosity, U (mm/s), f / CK | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %.1f | %.2f | %.4f | %.4f | %.4f | %.5g | %.5g | %.3f | %.3f | %.4f, %.4f, %.3f | %.0f |" % (
            "x".join(str(int(c)) for c in r["cells"]), r["cells_per_short_axis"], 1e3 * r["bed_top"], r["porosity"],
            1e3 * r["U"], r["Re"], r["drag_per_volume"], r["carman_kozeny"], r["ratio_ck"], r["ratio_ergun"],
            r["core_porosity"], 1e3 * r["core_U"], r["core_ratio_ck"], r["wall_seconds"]))


def study(args):
    env = dict(os.environ)
    binary = os.environ.get("TESSERA_BIN", os.path.join(ROOT, "build", "bin", "tessera"))
    mpirun = ["mpirun", "-n", str(args.ranks)]
    bed = os.path.join(args.out, "bed")
    if not os.path.exists(os.path.join(bed, "checkpoint.h5")):
        subprocess.run(mpirun + [binary, "run", os.path.join(ROOT, "cases/coupled/packed_bed_prepare.yaml"),
                                 "--output", bed, "--quiet"], check=True, env=env)
    rows = []
    for per in [float(c) for c in args.cells.split(",")]:
        h = 1.04e-3 / per
        n = [max(1, round(10.4e-3 / h)), max(1, round(10.4e-3 / h)), max(1, round(16e-3 / h))]
        run = os.path.join(args.out, "h%g" % per)
        if not os.path.exists(os.path.join(run, "summary.json")) or args.rerun:
            subprocess.run(mpirun + [binary, "run", os.path.join(ROOT, "cases/coupled/packed_bed.yaml"), "--output", run,
                                     "--quiet", "--set", "bodies.file=" + os.path.abspath(os.path.join(bed, "checkpoint.h5")),
                                     "--set", "fluid.cells=[%d,%d,%d]" % tuple(n)], check=True, env=env)
        rows.append(measure(run))
    print_rows(rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 4))
    x = [r["cells_per_short_axis"] for r in rows]
    ax.plot(x, [r["ratio_ck"] for r in rows], "o-", label="Tessera / Carman-Kozeny (180)")
    ax.plot(x, [r["ratio_ergun"] for r in rows], "s--", label="Tessera / Ergun viscous term (150)")
    ax.plot(x, [r["core_ratio_ck"] for r in rows], "^-", label="the core (a short axis from the walls) / Carman-Kozeny")
    ax.axhline(1, color="k", lw=0.8)
    ax.set_ylim(0, 1.1)
    ax.set_xlabel("cells per grain short axis")
    ax.set_ylabel("drag per unit bed volume, ratio")
    ax.set_title("creeping flow through the packed bed (porosity %.2f)" % rows[-1]["porosity"])
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.png or os.path.join(args.out, "packed_bed.png"), dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*")
    ap.add_argument("--study", action="store_true")
    ap.add_argument("--out", default="runs/packed_bed")
    ap.add_argument("--cells", default="2,3,4.5,6")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--rerun", action="store_true")
    ap.add_argument("--png")
    args = ap.parse_args()
    if args.study:
        study(args)
    elif args.runs:
        print_rows([measure(r) for r in args.runs])
    else:
        ap.error("give run directories or --study")


if __name__ == "__main__":
    sys.exit(main())
