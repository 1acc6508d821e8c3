#!/usr/bin/python3
"""Render a slice of a flow run's fields to PNG: liquid fraction in colour, velocity arrows.

Usage: flow_slice.py RUN_DIR [--axis x|y|z] [--at POSITION_M] [--snapshot N|all] [--out FILE.png]
       [--arrows 24] [--scale S] [--times 0,0.02,0.19] [--field NAME]
RUN_DIR/fields/fields_NNNNN.h5 (written by output.snapshot_interval). The slice is the cell plane
nearest POSITION_M along AXIS (default: the middle). With --snapshot all, one PNG per snapshot
(FILE_NNNNN.png) and a strip of up to six of them side by side (FILE), as the drop-impact seed's
figures 8-12 show the splash in time. --times T1,T2,...: the snapshots nearest those times (s), side
by side. A coupled run's solid fraction (the grains) is drawn in brown under the water.
--field NAME colours another cell scalar of the snapshots instead, on a diverging scale symmetric
about 0 with its colour bar (e.g. advection_energy_source of fluid.energy_budget, theory F12a: where
the advection makes or loses kinetic energy, J/m^3 since the start); --arrows 0 draws no arrows."""
import argparse, glob, os, re, sys

import h5py
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
import numpy as np
import xml.etree.ElementTree as ET


def grid_of(run_dir):
    """Origin and spacing (x, y, z) from fields.xmf."""
    root = ET.parse(os.path.join(run_dir, 'fields', 'fields.xmf')).getroot()
    geom = root.find('.//Geometry')
    items = geom.findall('DataItem')
    oz, oy, ox = (float(v) for v in items[0].text.split())
    dz, dy, dx = (float(v) for v in items[1].text.split())
    return np.array([ox, oy, oz]), np.array([dx, dy, dz])


def load(path):
    # (z, y, x[, 3]). Coupled runs: the solid fraction, and the liquid content (liquid volume over the
    # cell's, theory C7; runs before 2026-11-29 lack it: the liquid fraction times the fluid part).
    with h5py.File(path, 'r') as f:
        solid = np.array(f['solid_fraction']) if 'solid_fraction' in f else None
        frac = np.array(f['liquid_fraction'])
        content = np.array(f['liquid_content']) if 'liquid_content' in f else None
        if solid is not None and content is None:
            content = frac * (1 - np.clip(solid, 0, 1))
        return f.attrs['time'], frac, np.array(f['velocity']), solid, content


def plane(a, axis, index):
    return a[index] if axis == 'z' else a[:, index, :] if axis == 'y' else a[:, :, index]


def slice_of(frac, vel, axis, index):
    # arrays are (z, y, x); returns 2-D (rows = vertical plot axis) and the plot's two axes
    if axis == 'z':
        return frac[index], vel[index][..., 0], vel[index][..., 1], (0, 1)
    if axis == 'y':
        return frac[:, index, :], vel[:, index, :, 0], vel[:, index, :, 2], (0, 2)
    return frac[:, :, index], vel[:, :, index, 1], vel[:, :, index, 2], (1, 2)


def draw(ax, run_dir, path, axis, at, arrows, scale, field=None):
    origin, h = grid_of(run_dir)
    t, frac, vel, solid, content = load(path)
    if field is not None:
        with h5py.File(path, 'r') as f:
            if field not in f:
                sys.exit('%s has no field %s (it has: %s)' % (path, field, ', '.join(f.keys())))
            values = np.array(f[field])
    n = {'x': frac.shape[2], 'y': frac.shape[1], 'z': frac.shape[0]}[axis]
    a = 'xyz'.index(axis)
    index = n // 2 if at is None else int(np.clip((at - origin[a]) / h[a], 0, n - 1))
    f2, u, v, (p, q) = slice_of(frac, vel, axis, index)
    extent = [origin[p], origin[p] + f2.shape[1] * h[p], origin[q], origin[q] + f2.shape[0] * h[q]]
    if field is not None:
        v2 = plane(values, axis, index)
        top = np.percentile(np.abs(v2), 99.5) or 1.0
        im = ax.imshow(v2, origin='lower', extent=[e * 1e3 for e in extent], cmap='RdBu', vmin=-top, vmax=top,
                       interpolation='nearest')
        plt.colorbar(im, ax=ax, shrink=0.8, label=field)
    elif solid is not None:  # grains (brown) under the water outside them (blue)
        s2 = np.clip(plane(solid, axis, index), 0, 1)
        ax.imshow(np.ma.masked_less(s2, 0.02), origin='lower', extent=[e * 1e3 for e in extent], cmap='copper_r',
                  vmin=0, vmax=1.2, interpolation='nearest')
        water = np.ma.masked_less(plane(content, axis, index), 0.01)
        ax.imshow(water, origin='lower', extent=[e * 1e3 for e in extent], cmap='Blues', vmin=0, vmax=1,
                  interpolation='nearest', alpha=0.85)
    else:
        ax.imshow(f2, origin='lower', extent=[e * 1e3 for e in extent], cmap='Blues', vmin=0, vmax=1,
                  interpolation='nearest')
    ax.contour(np.linspace(extent[0], extent[1], f2.shape[1]) * 1e3, np.linspace(extent[2], extent[3], f2.shape[0]) * 1e3,
               f2, levels=[0.5], colors='k', linewidths=0.6)
    if arrows > 0:
        draw_arrows(ax, origin, h, f2, u, v, p, q, arrows, scale)
    ax.set_title('t = %.4g ms' % (t * 1e3))
    ax.set_xlabel('%s [mm]' % 'xyz'[p])
    ax.set_ylabel('%s [mm]' % 'xyz'[q])
    ax.set_aspect('equal')


def draw_arrows(ax, origin, h, f2, u, v, p, q, arrows, scale):
    sx, sy = max(1, f2.shape[1] // arrows), max(1, f2.shape[0] // arrows)
    X, Y = np.meshgrid((origin[p] + (np.arange(f2.shape[1]) + 0.5) * h[p]) * 1e3,
                       (origin[q] + (np.arange(f2.shape[0]) + 0.5) * h[q]) * 1e3)
    ax.quiver(X[::sy, ::sx], Y[::sy, ::sx], u[::sy, ::sx], v[::sy, ::sx], color='tab:red', scale=scale,
              width=0.003)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('run_dir')
    ap.add_argument('--axis', default='y', choices='xyz')
    ap.add_argument('--at', type=float)
    ap.add_argument('--snapshot', default='last')
    ap.add_argument('--out', default='slice.png')
    ap.add_argument('--arrows', type=int, default=24)
    ap.add_argument('--scale', type=float, default=None)
    ap.add_argument('--times', help='comma-separated times (s): the nearest snapshots, side by side')
    ap.add_argument('--field', help='colour this cell scalar instead of the liquid fraction')
    args = ap.parse_args()
    files = sorted(glob.glob(os.path.join(args.run_dir, 'fields', 'fields_*.h5')))
    if not files:
        sys.exit('no fields in %s/fields: set output.snapshot_interval' % args.run_dir)
    if args.times:
        times = [h5py.File(p, 'r').attrs['time'] for p in files]
        pick = [files[int(np.argmin([abs(t - float(w)) for t in times]))] for w in args.times.split(',')]
        fig, axes = plt.subplots(1, len(pick), figsize=(4.2 * len(pick), 3.6))
        for ax, path in zip(np.atleast_1d(axes), pick):
            draw(ax, args.run_dir, path, args.axis, args.at, args.arrows, args.scale, args.field)
        fig.tight_layout()
        fig.savefig(args.out, dpi=110)
    elif args.snapshot == 'all':
        base, ext = os.path.splitext(args.out)
        for path in files:
            fig, ax = plt.subplots(figsize=(5, 4.5))
            draw(ax, args.run_dir, path, args.axis, args.at, args.arrows, args.scale, args.field)
            fig.tight_layout()
            fig.savefig('%s_%s%s' % (base, re.search(r'(\d+)\.h5$', path).group(1), ext), dpi=110)
            plt.close(fig)
        pick = [files[int(round(i * (len(files) - 1) / 5))] for i in range(min(6, len(files)))]
        fig, axes = plt.subplots(1, len(pick), figsize=(3.2 * len(pick), 3.4))
        for ax, path in zip(np.atleast_1d(axes), pick):
            draw(ax, args.run_dir, path, args.axis, args.at, args.arrows, args.scale, args.field)
        fig.tight_layout()
        fig.savefig(args.out, dpi=110)
    else:
        path = files[-1] if args.snapshot == 'last' else files[int(args.snapshot)]
        fig, ax = plt.subplots(figsize=(5.5, 5))
        draw(ax, args.run_dir, path, args.axis, args.at, args.arrows, args.scale, args.field)
        fig.tight_layout()
        fig.savefig(args.out, dpi=120)
    print('wrote', args.out)


if __name__ == '__main__':
    main()
