#!/usr/bin/python3
"""Pictures of a bed: side view of a slice and the solid-fraction profile over height.

usage: tools/plot_bed.py RUN_DIR [--out FILE.png]
Reads RUN_DIR/bed.data (LAMMPS data file written by the deposition scene) and RUN_DIR/summary.json.
Needs Debian's python3-numpy and python3-matplotlib (tools/setup.sh installs them).
"""
import argparse
import json
import os
import sys

try:
    import numpy as np
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle
except ImportError:
    sys.exit("plot_bed.py: needs python3-numpy and python3-matplotlib (apt-get install python3-matplotlib)")


def read_bed(path):
    rows, box, section = [], {}, None
    with open(path) as f:
        for line in f:
            s = line.split("#")[0].split()
            if not s:
                continue
            if s[0] == "Atoms":
                section = "atoms"
                continue
            if s[0][0].isalpha():
                section = None
                continue
            if len(s) >= 4 and s[-2].endswith("lo") and s[-1].endswith("hi"):
                box[s[-2][0]] = (float(s[0]), float(s[1]))
            elif section == "atoms":
                rows.append([float(v) for v in s[:7]])
    return np.array(rows), box


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run_dir")
    ap.add_argument("--out")
    a = ap.parse_args()
    bed, box = read_bed(os.path.join(a.run_dir, "bed.data"))
    d, x, y, z = bed[:, 2], bed[:, 4], bed[:, 5], bed[:, 6]
    summary = {}
    if os.path.exists(os.path.join(a.run_dir, "summary.json")):
        with open(os.path.join(a.run_dir, "summary.json")) as f:
            summary = json.load(f)
    q = summary.get("quantities", {})

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 5), gridspec_kw={"width_ratios": [2, 1]})
    ymid, dm = 0.5 * (box["y"][0] + box["y"][1]), np.median(d)
    sl = np.abs(y - ymid) < 1.5 * dm
    circles = [Circle((xi * 1e3, zi * 1e3), 0.5 * di * 1e3) for xi, zi, di in zip(x[sl], z[sl], d[sl])]
    pc = PatchCollection(circles, cmap="viridis", edgecolor="k", linewidth=0.2)
    pc.set_array((y[sl] - ymid) * 1e3)
    ax1.add_collection(pc)
    ax1.set_xlim(box["x"][0] * 1e3, box["x"][1] * 1e3)
    ax1.set_ylim(box["z"][0] * 1e3, (z.max() + dm) * 1e3)
    ax1.set_aspect("equal")
    ax1.set_xlabel("x (mm)")
    ax1.set_ylabel("z (mm)")
    ax1.set_title(f"slice |y - y_mid| < 1.5 d: {sl.sum()} of {len(d)} grains")
    fig.colorbar(pc, ax=ax1, label="y - y_mid (mm)", shrink=0.8)

    area = (box["x"][1] - box["x"][0]) * (box["y"][1] - box["y"][0])
    edges = np.arange(box["z"][0], z.max() + dm, dm)
    vol = np.pi / 6 * d ** 3
    phi = np.histogram(z, bins=edges, weights=vol)[0] / (area * dm)
    ax2.plot(phi, 0.5 * (edges[1:] + edges[:-1]) * 1e3, "-o", ms=3)
    if "packing_fraction" in q:
        ax2.axvline(q["packing_fraction"], color="r", ls="--", label=f"bulk {q['packing_fraction']:.3f}")
        ax2.legend(loc="lower left")
    ax2.set_xlabel("solid fraction (whole cross-section, slabs of d)")
    ax2.set_ylabel("z (mm)")
    ax2.set_xlim(0, 0.8)
    ax2.grid(alpha=0.3)
    title = f"{len(d)} grains"
    if q:
        title += f", coordination {q.get('coordination_number', 0):.2f}, settled at {q.get('settle_time', 0):.3f} s"
    fig.suptitle(title)
    fig.tight_layout()
    out = a.out or os.path.join(a.run_dir, "bed.png")
    fig.savefig(out, dpi=120)
    print(out)


if __name__ == "__main__":
    main()
