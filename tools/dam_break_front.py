#!/usr/bin/python3
"""Water-front position of a dam-break run against Martin & Moyce (1952).

Usage: dam_break_front.py RUN_DIR [--a 0.146] [--g 9.81] [--png FILE] [--label NAME] [--foam FILE]
Reads RUN_DIR/series.csv (time, front_position), forms T = t sqrt(2g/a) and Z = x/a, interpolates
Z(T) at the reference's T values and prints the table and the mean and maximum |dZ|/Z_ref.
Reference points whose Z is beyond the tank (Z > 4 - 0.1) are left out: the 4a tank stops the front.
--also DIR:LABEL: another Tessera run (e.g. with the wall law) on the same plot.
--foam FILE: a front_position.py output (t T Z rows) of interFoam, put on the same plot and table.
Prints, last: `front_error_mean: X` (mean relative error over the points compared)."""
import argparse, csv, math, os, sys

HERE = os.path.dirname(os.path.abspath(__file__))
REF = os.path.join(HERE, '..', '..', 'shared', 'reference', 'martin_moyce_1952_front.csv')


def reference(path=REF):
    rows = []
    for line in open(path):
        if line.startswith('#') or line.startswith('T'):
            continue
        T, Z = (float(v) for v in line.split(','))
        rows.append((T, Z))
    return rows


def interp(xs, ys, x):
    if x <= xs[0]:
        return ys[0]
    for i in range(1, len(xs)):
        if x <= xs[i]:
            w = (x - xs[i - 1]) / (xs[i] - xs[i - 1])
            return ys[i - 1] + w * (ys[i] - ys[i - 1])
    return None


def errors(T, Z, ref, tank=4.0):
    out = []
    for Tr, Zr in ref:
        if Tr <= 0 or Zr > tank - 0.1:
            continue
        z = interp(T, Z, Tr)
        if z is not None:
            out.append((Tr, Zr, z, abs(z - Zr) / Zr))
    return out


def load_run(run_dir, a, g):
    T, Z = [], []
    with open(os.path.join(run_dir, 'series.csv')) as f:
        for row in csv.DictReader(f):
            T.append(float(row['time']) * math.sqrt(2 * g / a))
            Z.append(float(row['front_position']) / a)
    return T, Z


def load_foam(path):
    T, Z = [], []
    for line in open(path):
        if line.startswith('#') or not line.strip():
            continue
        t, TT, ZZ = (float(v) for v in line.split())
        T.append(TT)
        Z.append(ZZ)
    return T, Z


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('run_dir')
    ap.add_argument('--a', type=float, default=0.146)
    ap.add_argument('--g', type=float, default=9.81)
    ap.add_argument('--png')
    ap.add_argument('--label', default='Tessera')
    ap.add_argument('--foam')
    ap.add_argument('--also', action='append', default=[], metavar='RUN_DIR:LABEL',
                    help='another Tessera run on the plot, with its mean error (repeatable)')
    ap.add_argument('--reference', default=REF)
    args = ap.parse_args()
    ref = reference(args.reference)
    T, Z = load_run(args.run_dir, args.a, args.g)
    e = errors(T, Z, ref)
    foam = load_foam(args.foam) if args.foam else None
    ef = errors(*foam, ref) if foam else None
    print('#    T   Z_ref   Z_%s  rel.err' % args.label + ('   Z_interFoam rel.err' if ef else ''))
    for n, (Tr, Zr, z, r) in enumerate(e):
        extra = ''
        if ef:
            m = [x for x in ef if x[0] == Tr]
            extra = '   %.3f  %.3f' % (m[0][2], m[0][3]) if m else ''
        print('%6.2f  %5.2f  %6.3f  %6.3f%s' % (Tr, Zr, z, r, extra))
    mean = sum(x[3] for x in e) / max(1, len(e))
    print('max relative error %.3f over %d points' % (max(x[3] for x in e), len(e)))
    if ef:
        print('interFoam: mean relative error %.3f, max %.3f' % (sum(x[3] for x in ef) / len(ef), max(x[3] for x in ef)))
    also = []
    for spec in args.also:
        d, _, label = spec.partition(':')
        TA, ZA = load_run(d, args.a, args.g)
        ea = errors(TA, ZA, ref)
        print('%s: mean relative error %.3f, max %.3f' % (label or d, sum(x[3] for x in ea) / len(ea),
                                                          max(x[3] for x in ea)))
        also.append((TA, ZA, label or d))
    if args.png:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(5.5, 4))
        ax.plot([r[0] for r in ref], [r[1] for r in ref], 'ko', label='Martin & Moyce (1952)')
        ax.plot(T, Z, '-', label=args.label)
        for TA, ZA, label in also:
            ax.plot(TA, ZA, '-.', label=label)
        if foam:
            ax.plot(foam[0], foam[1], '--', label='interFoam')
        ax.set_xlabel('T = t sqrt(2g/a)')
        ax.set_ylabel('Z = x_front / a')
        ax.set_xlim(0, 3.6)
        ax.set_ylim(1, 4.2)
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)
    print('front_error_mean: %.4f' % mean)


if __name__ == '__main__':
    sys.exit(main())
