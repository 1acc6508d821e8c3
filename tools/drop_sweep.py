#!/usr/bin/python3
"""Drop-on-sand runs in batches: the seed's series (Table 2, Fig. 15) and the speed-against-error study.

Series (`--set-of series`): a sphere (D_H / D_V = 1.0) at 2.25, 4.5, 6.75 and 9.0 m/s (mv about 20, 40,
60, 80 g cm/s) and spheroids of D_H / D_V = 1.6 and 2.0 at 2.25 and 9.0 m/s; the seed's mass.
Study (`--set-of study`): one factor at a time around the case (9 m/s sphere): DEM sub-steps per flow
step (the DEM's own count, 100, 200; the seed used 325), the grid (48 x 48 x 36, 64 x 64 x 48, 80 x 80
x 60), contact spheres per grain (75, 30), contact stiffness (1e3, 1e4, 1e5 N/m; each with its own
bed), and four more beds of other random orientations (deposition.seed) for the scatter of V.

Each run is a bed (made once per distinct bed from --bed-case, under OUT/beds) and the impact.

Usage: drop_sweep.py run   [--set-of series|study] [--case cases/drop_on_sand/small.yaml]
                           [--bed-case cases/drop_on_sand/bed_small.yaml] [--out runs/drop_sweep]
                           [--ranks 2] [--only NAME,...] [--set KEY=VALUE ...] [--bed-set KEY=VALUE ...]
           Runs the runs here, one after the other (one whose summary.json exists is skipped).
           --set goes to every impact, --bed-set to every bed (e.g. --bed-set deposition.seed=1: the
           series again on a bed of other grain orientations, in its own OUT).
       drop_sweep.py slurm [same options] [--partition P] [--time 04:00:00] [--tasks 16]
           Writes OUT/runs.txt and OUT/sweep.slurm: a job array of one task per run (sbatch it).
       drop_sweep.py plot  [--set-of series|study] [--out OUT[,OUT2,...]]
           series: the table (aspect, v, mv, V by eqs. 14 and 13, L, H, the bed's V before the drop,
           displaced grains, wall) in OUT/table.md and V against mv per shape in
           OUT/crater_vs_momentum.png (Fig. 15); with several OUTs (the series on several beds),
           each point's values on every bed, their mean and range, in the first OUT's
           table_beds.md and crater_vs_momentum_beds.png. study: each run's V and displaced-grain count
           against the mean and standard deviation of the orientation repeats (the base run among
           them), and V against its wall time, in OUT/study.md and OUT/study.png.
"""
import argparse, fcntl, glob, json, math, os, shlex, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TESSERA = os.environ.get('TESSERA', os.path.join(ROOT, 'build', 'bin', 'tessera'))


def stiffness(k):
    sets = []
    for pair in (0, 1):
        sets += ['solid.contact.pairs.%d.normal_stiffness=%g' % (pair, k),
                 'solid.contact.pairs.%d.tangential_stiffness=%g' % (pair, k)]
    return sets


def runs_of(which):
    """(name, its bed: (bed name, bed overrides), impact overrides)."""
    if which == 'series':
        pts = [(1.0, 2.25), (1.0, 4.5), (1.0, 6.75), (1.0, 9.0), (1.6, 2.25), (1.6, 9.0), (2.0, 2.25), (2.0, 9.0)]
        return [('ar%.1f_v%.2f' % (a, v), ('case', []), ['drop.aspect_ratio=%g' % a, 'drop.velocity=%g' % v]) for a, v in pts]
    spheres = ['solid.shapes.0.contact_spheres.count=30']
    case = ('case', [])
    return ([('base', case, []),
             ('substeps_100', case, ['coupling.substeps=100']),
             ('substeps_200', case, ['coupling.substeps=200']),
             ('cells_48', case, ['fluid.cells=[48, 48, 36]']),
             ('cells_80', case, ['fluid.cells=[80, 80, 60]']),
             ('spheres_30', ('spheres_30', spheres), spheres),
             ('stiffness_1e3', ('stiffness_1e3', stiffness(1e3)), stiffness(1e3)),
             ('stiffness_1e5', ('stiffness_1e5', stiffness(1e5)), stiffness(1e5))] +
            [('orientation_%d' % s, ('seed_%d' % s, ['deposition.seed=%d' % s]), []) for s in (1, 2, 3, 4)])


def mpirun(ranks):
    return ['mpirun', '-n', str(ranks)]


def sh(cmd):
    print(' '.join(shlex.quote(c) for c in cmd), flush=True)
    subprocess.run(cmd, check=True)


def run(args):
    selected = [r for r in runs_of(args.set_of) if not args.only or r[0] in args.only.split(',')]
    for name, bed_spec, sets in selected:
        out = os.path.join(args.out, name)
        if os.path.exists(os.path.join(out, 'summary.json')):
            print('done already:', out)
            continue
        bed_name, bed_sets = bed_spec
        bed = os.path.join(args.out, 'beds', bed_name)
        os.makedirs(os.path.dirname(bed), exist_ok=True)
        with open(bed + '.lock', 'w') as lock:  # array tasks that share a bed make it once
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not os.path.exists(os.path.join(bed, 'summary.json')):
                sh(mpirun(args.ranks) + [TESSERA, 'run', args.bed_case, '--output', bed] +
                   sum((['--set', s] for s in bed_sets + (args.bed_set or [])), []))
        extra = ['bodies.file=' + os.path.abspath(os.path.join(bed, 'checkpoint.h5'))]
        sh(mpirun(args.ranks) + [TESSERA, 'run', args.case, '--output', out] +
           sum((['--set', s] for s in sets + extra + (args.set or [])), []))


def slurm(args):
    os.makedirs(args.out, exist_ok=True)
    names = [r[0] for r in runs_of(args.set_of) if not args.only or r[0] in args.only.split(',')]
    with open(os.path.join(args.out, 'runs.txt'), 'w') as f:
        f.write('\n'.join(names) + '\n')
    extra = ' '.join(['--set %s' % shlex.quote(s) for s in args.set or []] +
                     ['--bed-set %s' % shlex.quote(s) for s in args.bed_set or []])
    out = os.path.abspath(args.out)
    script = f"""#!/bin/bash
#SBATCH --job-name=drop_{args.set_of}
#SBATCH --array=1-{len(names)}
#SBATCH --ntasks={args.tasks}
#SBATCH --time={args.time}
#SBATCH --output={out}/slurm_%a.log
{('#SBATCH --partition=' + args.partition) if args.partition else ''}
name=$(sed -n "${{SLURM_ARRAY_TASK_ID}}p" {out}/runs.txt)
cd {ROOT}
python3 tools/drop_sweep.py run --set-of {args.set_of} --case {os.path.abspath(args.case)} \\
  --bed-case {os.path.abspath(args.bed_case)} --out {out} --ranks $SLURM_NTASKS --only "$name" {extra}
"""
    path = os.path.join(args.out, 'sweep.slurm')
    with open(path, 'w') as f:
        f.write(script)
    print('wrote', path, '(sbatch it);', len(names), 'runs')


def first_volume(run_dir):
    """The crater measure of the bed before the drop: crater.csv's first row (t = 0)."""
    with open(os.path.join(run_dir, 'crater.csv')) as f:
        f.readline()
        return float(f.readline().split(',')[1])


def collect(out):
    rows = {}
    for path in sorted(glob.glob(os.path.join(out, '*', 'summary.json'))):
        s = json.load(open(path))
        q = s['quantities']
        if 'crater_volume' not in q:
            continue
        rows[os.path.basename(os.path.dirname(path))] = dict(
            aspect=q['drop_horizontal_diameter'] / q['drop_vertical_diameter'], v=q['drop_velocity'],
            mv=q['drop_momentum'] * 1e5, V=q['crater_volume'] * 1e9, V13=q['crater_section_volume'] * 1e9,
            V0=first_volume(os.path.dirname(path)) * 1e9, L=q['crater_rim_radius'] * 1e3, H=q['crater_depth'] * 1e3,
            moved=q.get('displaced_grains', -1), t=s['time'], wall=s['wall_seconds'], status=s['status'])
    if not rows:
        sys.exit('no finished runs under ' + out)
    return rows


def plot_series(args, rows):
    lines = ['| D_H/D_V | v (m/s) | mv (g cm/s) | V eq. 14 (mm^3) | V eq. 13 (mm^3) | L (mm) | H (mm) | V of the bed before (mm^3) | displaced grains | t end (s) | wall (s) | status |',
             '|' + '---|' * 12]
    for r in sorted(rows.values(), key=lambda r: (r['aspect'], r['v'])):
        lines.append('| %.1f | %.2f | %.1f | %.1f | %.1f | %.2f | %.2f | %.1f | %d | %.3f | %.0f | %s |' % (
            r['aspect'], r['v'], r['mv'], r['V'], r['V13'], r['L'], r['H'], r['V0'], r['moved'], r['t'], r['wall'],
            r['status']))
    text = '\n'.join(lines)
    print(text)
    open(os.path.join(args.out, 'table.md'), 'w').write(text + '\n')
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for aspect, marker in ((1.0, 'o'), (1.6, 's'), (2.0, '^')):
        pts = sorted((r for r in rows.values() if abs(r['aspect'] - aspect) < 0.05), key=lambda r: r['mv'])
        if pts:
            ax.plot([r['mv'] for r in pts], [r['V'] for r in pts], marker + '-', label='D_H/D_V = %.1f' % aspect)
    ax.set_xlabel('drop momentum mv [g cm/s]')
    ax.set_ylabel('crater volume V [mm$^3$] (eq. 14)')
    ax.set_title('crater volume against momentum (seed Fig. 15)')
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, 'crater_vs_momentum.png'), dpi=120)
    print('wrote', os.path.join(args.out, 'crater_vs_momentum.png'))


def plot_series_beds(args, outs):
    """The series on several beds: each point's V (eq. 14) and displaced grains on every bed that ran
    it (a bed may run only some points), with their mean, range and standard deviation; the figure
    draws each shape's mean with the range as error bars."""
    per_bed = [collect(o) for o in outs]
    every = {n: r for b in per_bed for n, r in b.items()}
    names = sorted(every, key=lambda n: (every[n]['aspect'], every[n]['v']))
    labels = [os.path.basename(os.path.normpath(o)) for o in outs]
    lines = ['beds: ' + ', '.join(labels), '',
             '| D_H/D_V | v (m/s) | mv (g cm/s) | beds | V eq. 14 per bed (mm^3) | mean (range) | sd | '
             'V eq. 13 mean (mm^3) | H mean (mm) | displaced grains per bed | mean |', '|' + '---|' * 11]
    stats = {}
    for n in names:
        rs = [b[n] for b in per_bed if n in b]
        cell = lambda key, fmt: ', '.join(fmt % b[n][key] if n in b else '-' for b in per_bed)
        V = [r['V'] for r in rs]
        moved = [r['moved'] for r in rs]
        m = sum(V) / len(V)
        sd = math.sqrt(sum((v - m) ** 2 for v in V) / (len(V) - 1)) if len(V) > 1 else float('nan')
        stats[n] = (rs[0]['aspect'], rs[0]['mv'], m, min(V), max(V))
        lines.append('| %.1f | %.2f | %.1f | %d | %s | %.1f (%.1f-%.1f) | %.1f | %.1f | %.2f | %s | %.1f |' % (
            rs[0]['aspect'], rs[0]['v'], rs[0]['mv'], len(rs), cell('V', '%.1f'), m, min(V), max(V), sd,
            sum(r['V13'] for r in rs) / len(rs), sum(r['H'] for r in rs) / len(rs),
            cell('moved', '%d'), sum(moved) / len(moved)))
    lines += ['', 'the measure on each bed before the drop (mm^3): ' +
              ', '.join('%.1f' % next(iter(b.values()))['V0'] for b in per_bed)]
    text = '\n'.join(lines)
    print(text)
    open(os.path.join(outs[0], 'table_beds.md'), 'w').write(text + '\n')
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for (aspect, marker), colour in zip(((1.0, 'o'), (1.6, 's'), (2.0, '^')), ('C0', 'C1', 'C2')):
        pts = sorted((st for st in stats.values() if abs(st[0] - aspect) < 0.05), key=lambda st: st[1])
        if not pts:
            continue
        mv = [st[1] for st in pts]
        ax.errorbar(mv, [st[2] for st in pts], yerr=[[st[2] - st[3] for st in pts], [st[4] - st[2] for st in pts]],
                    fmt=marker + '-', color=colour, capsize=3, label='D_H/D_V = %.1f, mean and range' % aspect)
    ax.set_xlabel('drop momentum mv [g cm/s]')
    ax.set_ylabel('crater volume V [mm$^3$] (eq. 14)')
    ax.set_title('crater volume against momentum, %d beds (seed Fig. 15)' % len(outs))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = os.path.join(outs[0], 'crater_vs_momentum_beds.png')
    fig.savefig(path, dpi=120)
    print('wrote', path)


def plot_study(args, rows):
    base = rows.get('base')
    if base is None:
        sys.exit('the study needs its base run')
    repeats = [r for n, r in rows.items() if n == 'base' or n.startswith('orientation_')]
    def spread(key):
        m = sum(r[key] for r in repeats) / len(repeats)
        return m, (math.sqrt(sum((r[key] - m) ** 2 for r in repeats) / (len(repeats) - 1)) if len(repeats) > 1
                   else float('nan'))
    mean, sd = spread('V')
    mean_moved, sd_moved = spread('moved')
    lines = ['scatter over %d beds of other orientations (the base run among them): V mean %.1f mm^3, standard '
             'deviation %.1f mm^3; displaced grains mean %.1f, standard deviation %.1f' % (
                 len(repeats), mean, sd, mean_moved, sd_moved), '',
             '| run | V (mm^3) | V - mean (mm^3) | within 2 sd | displaced grains | within 2 sd | wall (s) | wall / base |',
             '|---|---|---|---|---|---|---|---|']
    for n, r in sorted(rows.items()):
        d, dm = r['V'] - mean, r['moved'] - mean_moved
        lines.append('| %s | %.1f | %+.1f | %s | %d | %s | %.0f | %.2f |' % (
            n, r['V'], d, 'yes' if abs(d) <= 2 * sd else 'no', r['moved'], 'yes' if abs(dm) <= 2 * sd_moved else 'no',
            r['wall'], r['wall'] / base['wall']))
    text = '\n'.join(lines)
    print(text)
    open(os.path.join(args.out, 'study.md'), 'w').write(text + '\n')
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for n, r in sorted(rows.items()):
        repeat = n == 'base' or n.startswith('orientation')
        ax.plot(r['wall'], r['V'] - mean, 'x' if repeat else 'o', color='k' if repeat else None)
        ax.annotate(n, (r['wall'], r['V'] - mean), fontsize=7, xytext=(3, 3), textcoords='offset points')
    if sd == sd:
        ax.axhspan(-2 * sd, 2 * sd, color='grey', alpha=0.2, label='2 sd of the orientation repeats')
        ax.legend(fontsize=8)
    ax.axhline(0, color='k', lw=0.5)
    ax.set_xlabel('wall time [s]')
    ax.set_ylabel('V - mean of the orientation repeats [mm$^3$]')
    ax.set_title('crater volume change per factor against its cost')
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, 'study.png'), dpi=120)
    print('wrote', os.path.join(args.out, 'study.png'))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('mode', choices=['run', 'slurm', 'plot'])
    ap.add_argument('--set-of', default='series', choices=['series', 'study'])
    ap.add_argument('--case', default=os.path.join(ROOT, 'cases', 'drop_on_sand', 'small.yaml'))
    ap.add_argument('--bed-case', default=os.path.join(ROOT, 'cases', 'drop_on_sand', 'bed_small.yaml'))
    ap.add_argument('--out')
    ap.add_argument('--ranks', type=int, default=2)
    ap.add_argument('--only')
    ap.add_argument('--set', action='append')
    ap.add_argument('--bed-set', action='append')
    ap.add_argument('--partition')
    ap.add_argument('--time', default='04:00:00')
    ap.add_argument('--tasks', type=int, default=16)
    args = ap.parse_args()
    args.out = args.out or os.path.join(ROOT, 'runs', 'drop_' + args.set_of)
    if args.mode == 'plot' and ',' in args.out:
        if args.set_of != 'series':
            sys.exit('several OUTs: the series only')
        plot_series_beds(args, args.out.split(','))
    elif args.mode == 'plot':
        rows = collect(args.out)
        (plot_series if args.set_of == 'series' else plot_study)(args, rows)
    else:
        {'run': run, 'slurm': slurm}[args.mode](args)


if __name__ == '__main__':
    main()
