#!/usr/bin/python3
"""The crater of a drop-impact run (cases/drop_on_sand): figures, and how the crater volume depends on
the smoothing settings.

Usage: crater.py RUN_DIR [--out FILE.png]
           The run's crater (summary.json, crater_rings.csv, crater_surface.csv, crater.csv, written by
           the coupled scene's `crater` section; theory D1-D6): prints V (eq. 14), L, H, a, b and the
           sections' V (eq. 13), draws the smoothed surface seen from above with the rim circle (the
           seed's Figs. 13-14), the ring profile with the cap of eq. 14, the two sections through the
           axis, and V against time (RUN_DIR/crater.png unless --out).
       crater.py RUN_DIR --study --cells 1e-3,2e-3,3e-3 --rings 0.5e-3,1e-3 [--layers 1.04e-3,1]
           Re-measures the run's last state with each combination of smoothing cell (Delta x*), ring
           width (dr) and surface layer, by restarting tessera from RUN_DIR/checkpoint.h5 with no step
           (the one implementation, src/analysis/bed_surface.cpp); prints a table and writes
           RUN_DIR/crater_study.json. With --start, the state at t = 0 instead (the bed before the
           drop: the method's reading of an undisturbed, rough surface). --case FILE restarts with that
           case file instead of RUN_DIR/case.resolved.yaml (with the run's own overrides as --set).
"""
import argparse, csv, itertools, json, math, os, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return float('nan')


def report(run):
    q = json.load(open(os.path.join(run, 'summary.json')))['quantities']
    print('crater_volume %.4g mm^3 (eq. 14; start %.4g)  L %.3f mm  H %.3f mm  a %.3f mm  b %.3f mm' % (
        q['crater_volume'] * 1e9, q.get('crater_volume_start', float('nan')) * 1e9, q['crater_rim_radius'] * 1e3,
        q['crater_depth'] * 1e3, q['crater_a'] * 1e3, q['crater_b'] * 1e3))
    print('section_volume %.4g mm^3 (eq. 13: L1 %.2f mm, L2 %.2f mm)' % (
        q['crater_section_volume'] * 1e9, q['crater_section']['L1'] * 1e3, q['crater_section']['L2'] * 1e3))
    if 'drop_momentum' in q:
        print('drop momentum %.1f g cm/s, bed top %.3f mm, porosity below %.1f mm %.3f' % (
            q['drop_momentum'] * 1e5, q['bed_top'] * 1e3, q['porosity_height'] * 1e3, q['bed_porosity_start']))
    return q


def figure(run, q, out):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    import numpy as np
    surf = read_csv(os.path.join(run, 'crater_surface.csv'))
    xs = np.array([num(r['x']) for r in surf]) * 1e3
    ys = np.array([num(r['y']) for r in surf]) * 1e3
    hs = np.array([num(r['height']) for r in surf]) * 1e3
    n = int(round(math.sqrt(len(hs))))
    X, Y, H = xs.reshape(n, n), ys.reshape(n, n), hs.reshape(n, n)
    rings = read_csv(os.path.join(run, 'crater_rings.csv'))
    r = np.array([num(x['radius']) for x in rings]) * 1e3
    h = np.array([num(x['height']) for x in rings]) * 1e3
    cx, cy = (v * 1e3 for v in q['crater_settings']['axis'])
    L, a, b = q['crater_rim_radius'] * 1e3, q['crater_a'] * 1e3, q['crater_b'] * 1e3
    fig, axs = plt.subplots(2, 2, figsize=(10, 8.5))
    ax = axs[0, 0]
    m = ax.pcolormesh(X, Y, np.ma.masked_invalid(H), shading='nearest', cmap='terrain')
    fig.colorbar(m, ax=ax, label='smoothed height h_s [mm]')
    t = np.linspace(0, 2 * np.pi, 200)
    ax.plot(cx + L * np.cos(t), cy + L * np.sin(t), 'k--', lw=1, label='rim, r = L')
    ax.set_aspect('equal')
    ax.set_xlabel('x [mm]')
    ax.set_ylabel('y [mm]')
    ax.set_title('smoothed surface (cell %.2g mm)' % (q['crater_settings']['cell'] * 1e3))
    ax.legend(loc='upper right', fontsize=8)
    ax = axs[0, 1]
    ax.plot(r, h, 'o-', ms=3, label='ring mean')
    # The cap of eq. 14: sphere through (0, b) and (L, a).
    Hd = a - b
    if Hd > 0 and L > 0:
        R = (L * L + Hd * Hd) / (2 * Hd)
        rr = np.linspace(0, L, 100)
        ax.plot(rr, b + R - np.sqrt(np.maximum(R * R - rr * rr, 0)), 'k--', lw=1, label='cap of eq. 14')
    ax.axhline(a, color='grey', lw=0.5)
    ax.axhline(b, color='grey', lw=0.5)
    ax.set_xlabel('r [mm]')
    ax.set_ylabel('ring height [mm]')
    ax.set_title('V = %.3g mm$^3$  (L %.2f, H %.2f mm)' % (q['crater_volume'] * 1e9, L, Hd))
    ax.legend(fontsize=8)
    ax = axs[1, 0]
    mid = n // 2
    ax.plot(X[mid, :], H[mid, :], 'o-', ms=3, label='along x (y = axis)')
    ax.plot(Y[:, mid], H[:, mid], 's-', ms=3, label='along y (x = axis)')
    ax.set_xlabel('position [mm]')
    ax.set_ylabel('h_s [mm]')
    ax.set_title('sections (eq. 13: V = %.3g mm$^3$)' % (q['crater_section_volume'] * 1e9))
    ax.legend(fontsize=8)
    ax = axs[1, 1]
    path = os.path.join(run, 'crater.csv')
    if os.path.exists(path):
        rows = read_csv(path)
        ax.plot([num(x['time']) * 1e3 for x in rows], [num(x['crater_volume']) * 1e9 for x in rows], 'o-', ms=3,
                label='eq. 14')
        ax.plot([num(x['time']) * 1e3 for x in rows], [num(x['section_volume']) * 1e9 for x in rows], 's-', ms=3,
                label='eq. 13')
        ax.legend(fontsize=8)
    ax.set_xlabel('t [ms]')
    ax.set_ylabel('V [mm$^3$]')
    ax.set_title('crater volume in time')
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print('wrote', out)


def remeasure(run, settings, start, mpirun, case=None):
    """The crater of the run's last state (or its start) with other settings: a restart with no step."""
    resolved = case or os.path.join(run, 'case.resolved.yaml')
    tag = '_'.join('%s%g' % (k[0], v) for k, v in sorted(settings.items()))
    out = os.path.join(run, 'crater_study', ('start_' if start else '') + tag)
    sets = ['--set', 'output.snapshot_interval=0', '--set', 'output.progress_interval=1000']
    summary = json.load(open(os.path.join(run, 'summary.json')))
    if 'bodies_file' in summary:  # relative in the case file, which now lies elsewhere
        sets += ['--set', 'bodies.file=' + summary['bodies_file']]
    sets += sum((['--set', 'crater.%s=%r' % (k, v)] for k, v in settings.items()), [])
    if start:  # one flow step from the bed (the drop has not reached it)
        cmd = mpirun + [os.path.join(ROOT, 'build', 'bin', 'tessera'), 'run', resolved, '--quiet', '--output', out,
                        '--set', 'run.max_steps=1'] + sets
    else:
        steps = summary['steps']
        cmd = mpirun + [os.path.join(ROOT, 'build', 'bin', 'tessera'), 'run', resolved, '--quiet', '--output', out,
                        '--restart', os.path.join(run, 'checkpoint.h5'), '--set', 'run.max_steps=%d' % steps] + sets
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return json.load(open(os.path.join(out, 'summary.json')))['quantities']


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('run_dir')
    ap.add_argument('--out')
    ap.add_argument('--study', action='store_true')
    ap.add_argument('--start', action='store_true')
    ap.add_argument('--cells', default='')
    ap.add_argument('--rings', default='')
    ap.add_argument('--layers', default='')
    ap.add_argument('--ranks', type=int, default=1)
    ap.add_argument('--case', help='the case file to restart with (default RUN_DIR/case.resolved.yaml)')
    args = ap.parse_args()
    if not args.study:
        q = report(args.run_dir)
        figure(args.run_dir, q, args.out or os.path.join(args.run_dir, 'crater.png'))
        return
    base = json.load(open(os.path.join(args.run_dir, 'summary.json')))['quantities']['crater_settings']
    lists = lambda s, d: [float(v) for v in s.split(',')] if s else [d]
    mpirun = ['mpirun', '-n', str(args.ranks)]
    rows = []
    print('%10s %10s %10s %12s %12s %9s %9s' % ('cell mm', 'dr mm', 'layer mm', 'V14 mm^3', 'V13 mm^3', 'L mm', 'H mm'))
    for cell, dr, layer in itertools.product(lists(args.cells, base['cell']), lists(args.rings, base['ring_width']),
                                             lists(args.layers, base['surface_layer'])):
        q = remeasure(args.run_dir, {'cell': cell, 'ring_width': dr, 'surface_layer': layer}, args.start, mpirun, args.case)
        rows.append({'cell': cell, 'ring_width': dr, 'surface_layer': layer, 'crater_volume': q['crater_volume'],
                     'crater_section_volume': q['crater_section_volume'], 'crater_rim_radius': q['crater_rim_radius'],
                     'crater_depth': q['crater_depth']})
        print('%10.3g %10.3g %10.3g %12.4g %12.4g %9.3f %9.3f' % (cell * 1e3, dr * 1e3, layer * 1e3,
              q['crater_volume'] * 1e9, q['crater_section_volume'] * 1e9, q['crater_rim_radius'] * 1e3,
              q['crater_depth'] * 1e3))
    path = os.path.join(args.run_dir, 'crater_study%s.json' % ('_start' if args.start else ''))
    json.dump(rows, open(path, 'w'), indent=1)
    print('wrote', path)


if __name__ == '__main__':
    main()
