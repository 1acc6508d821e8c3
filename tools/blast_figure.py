#!/usr/bin/env python3
"""The blast scene's cracks and time-step levels, seen along the borehole (the seed's Figs. 12-13).

usage: tools/blast_figure.py RUN_DIR [RUN_DIR ...] --out FIGURE.png [--time T] [--labels A,B]
                             [--window X0,X1,Y0,Y1]

--window: the part of the plane drawn (m; default: every element, fragments far from the block
included); the title then counts the elements outside it.

For each run: the snapshot nearest T (default: the last); left column: the released faces (cracks)
cut by the block's mid-depth plane, over the elements' displacement (each drawn as its shadow on
the plane); right column: each
element's time-step level (0 = the macro step; k: dt0 / 2^k).
"""
import argparse
import glob
import os

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402


def snapshot(run, time):
    files = sorted(glob.glob(os.path.join(run, "elements_*.h5")))
    if not files:
        raise SystemExit(f"{run}: no elements_*.h5 snapshots")
    times = [h5py.File(f, "r").attrs["time"] for f in files]
    k = len(files) - 1 if time is None else int(np.argmin([abs(t - time) for t in times]))
    return h5py.File(files[k], "r"), times[k]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--time", type=float)
    ap.add_argument("--labels")
    ap.add_argument("--window", help="X0,X1,Y0,Y1 in m")
    a = ap.parse_args()
    window = [float(v) for v in a.window.split(",")] if a.window else None
    labels = a.labels.split(",") if a.labels else [os.path.basename(r.rstrip("/")) for r in a.runs]
    fig, axes = plt.subplots(len(a.runs), 2, figsize=(11, 5 * len(a.runs)), squeeze=False)
    for row, (run, label) in enumerate(zip(a.runs, labels)):
        h, t = snapshot(run, a.time)
        nodes = h["nodes"][:].reshape(-1, 4, 3)
        disp = np.linalg.norm(h["displacement"][:], axis=1)
        level = h["dt_level"][:].ravel()
        # Each element drawn as its projection on the xy plane (the hull of its 4 vertices' shadows).
        polys = []
        for tet in nodes[:, :, :2]:
            c = tet.mean(0)
            ang = np.arctan2(tet[:, 1] - c[1], tet[:, 0] - c[0])
            polys.append(tet[np.argsort(ang)])
        ax = axes[row][0]
        pc = PolyCollection(polys, array=1e3 * disp, cmap="Greys", edgecolors="none", alpha=0.6)
        pc.set_clim(0, np.percentile(1e3 * disp, 98))
        ax.add_collection(pc)
        fig.colorbar(pc, ax=ax, label="displacement (mm)", shrink=0.8)
        # Cracks: the released faces cut by the block's mid-depth plane (a quasi-2D section).
        zc = 0.5 * (nodes[:, :, 2].min() + nodes[:, :, 2].max())
        segs = []
        if "crack_nodes" in h and h["crack_nodes"].shape[0] > 0:
            for tri in h["crack_nodes"][:].reshape(-1, 3, 3):
                pts = []
                for i in range(3):
                    p, q = tri[i], tri[(i + 1) % 3]
                    if (p[2] - zc) * (q[2] - zc) < 0:
                        s = (zc - p[2]) / (q[2] - p[2])
                        pts.append((p + s * (q - p))[:2])
                if len(pts) == 2:
                    segs.append(pts)
            ax.add_collection(LineCollection(segs, colors="crimson", linewidths=1.2))
        outside = ""
        if window:
            c = nodes.mean(1)
            n_out = int(((c[:, 0] < window[0]) | (c[:, 0] > window[1]) | (c[:, 1] < window[2]) |
                         (c[:, 1] > window[3])).sum())
            outside = f", {n_out} elements outside the window"
        ax.set_title(f"{label}: cracks at mid-depth, t = {1e3 * t:.3g} ms\n"
                     f"({h['crack_nodes'].shape[0] // 3} released faces{outside})")
        ax.set_aspect("equal")
        ax.autoscale()
        if window:
            ax.set_xlim(window[0], window[1]), ax.set_ylim(window[2], window[3])
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax = axes[row][1]
        pc = PolyCollection(polys, array=level, cmap="viridis", edgecolors="k", linewidths=0.1)
        ax.add_collection(pc)
        fig.colorbar(pc, ax=ax, label="level k (dt0 / 2^k)", shrink=0.8)
        ax.set_title(f"{label}: time-step levels at t = {1e3 * t:.3g} ms")
        ax.set_aspect("equal")
        ax.autoscale()
        if window:
            ax.set_xlim(window[0], window[1]), ax.set_ylim(window[2], window[3])
        ax.set_xlabel("x (m)")
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
