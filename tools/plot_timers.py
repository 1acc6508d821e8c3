#!/usr/bin/python3
"""Per-phase wall time of a run as min / avg / max over ranks (the bunker-shot seed's Fig. 10),
from its summary.json: a table on stdout (markdown) and, with --png, a bar chart.

The DEM's phases group as the seed's: communication (ghost_comm, migration, reduction), contact
computation (contact_forces, wall_forces), cell search (neighbor), integration (integrate), output.

usage: tools/plot_timers.py RUN_DIR/summary.json [--png FILE] [--title TEXT]
"""
import argparse
import json

GROUPS = [("communication", ["ghost_comm", "migration", "reduction"]),
          ("contact computation", ["contact_forces", "wall_forces"]),
          ("cell search", ["neighbor"]),
          ("integration", ["integrate"]),
          ("output", ["output"])]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("summary")
    ap.add_argument("--png")
    ap.add_argument("--title", default="")
    args = ap.parse_args()
    s = json.load(open(args.summary))
    t = s["timers"]
    print("%d ranks, %d steps, loop %.1f s" % (s["ranks"], s.get("steps_this_run", s["steps"]), s["loop_seconds"]))
    print("| phase | timers | min (s) | avg (s) | max (s) |\n|---|---|---|---|---|")
    rows = []
    known = set()
    for name, keys in GROUPS:
        present = [k for k in keys if k in t]
        known.update(present)
        if not present:
            continue
        # Sums of per-rank min/avg/max bound the group's; avg adds exactly.
        row = (name, ", ".join(present), sum(t[k]["min"] for k in present), sum(t[k]["avg"] for k in present),
               sum(t[k]["max"] for k in present))
        rows.append(row)
        print("| %s | %s | %.2f | %.2f | %.2f |" % row)
    for k in sorted(set(t) - known):
        row = (k, k, t[k]["min"], t[k]["avg"], t[k]["max"])
        rows.append(row)
        print("| %s | %s | %.2f | %.2f | %.2f |" % row)
    if args.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 3.6))
        x = range(len(rows))
        w = 0.27
        ax.bar([i - w for i in x], [r[2] for r in rows], w, label="min")
        ax.bar(list(x), [r[3] for r in rows], w, label="avg")
        ax.bar([i + w for i in x], [r[4] for r in rows], w, label="max")
        ax.set_xticks(list(x))
        ax.set_xticklabels([r[0] for r in rows], rotation=20, ha="right", fontsize=8)
        ax.set_ylabel("wall time (s)")
        ax.set_title(args.title or "%s on %d ranks: time per phase over ranks" % (s["scene"], s["ranks"]), fontsize=9)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3, axis="y")
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)


if __name__ == "__main__":
    main()
