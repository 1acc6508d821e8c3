#!/usr/bin/python3
"""Time per rank of one or more runs, side by side (the blast seed's Fig. 15: each rank's time with
and without rebalancing), from the per-rank timers of their summary.json files: a table on stdout
and, with --png, stacked bars per rank (computation, cell search and integration, communication,
and the wait at the rebuild check's reduction; for a coupled run: the flow and coupling stages, the
DEM, and the communication with its waits).

usage: tools/plot_ranks.py RUN_A/summary.json [RUN_B/summary.json ...] [--labels A,B] [--png FILE]
"""
import argparse
import json

GROUPS = [("contact computation", ["contact_forces", "wall_forces"]),
          ("integration and cell search", ["integrate", "neighbor"]),
          ("communication", ["ghost_comm", "migration"]),
          ("waiting (reduction)", ["reduction"])]
# A coupled run (its timers hold the DEM's under dem/ and the flow's under flow/). The flow's ghost
# exchanges are timed inside the flow's phases and the coupling's stages alike, waits included: they
# are taken out of those (a key with a leading "-") and shown with the DEM's communication and waits.
COUPLED_GROUPS = [("flow and coupling stages (solid fraction, force, pore liquid, correction)",
                   ["flow/advection", "flow/poisson", "flow/projection", "flow/viscous", "solid_fraction",
                    "fluid_force", "pore_liquid", "correction", "-flow/halo_exchange_fields",
                    "-flow/halo_exchange_multigrid"]),
                  ("DEM (contacts, integration, cell search)",
                   ["dem/contact_forces", "dem/wall_forces", "dem/integrate", "dem/neighbor"]),
                  ("communication and waiting (ghost exchanges, migration, reductions)",
                   ["flow/halo_exchange_fields", "flow/halo_exchange_multigrid", "dem/ghost_comm", "dem/migration",
                    "dem/reduction"])]


def per_rank(summary):
    t = summary["timers"]
    ranks = summary["ranks"]
    out = []
    for name, keys in (COUPLED_GROUPS if "dem_substeps" in t else GROUPS):
        values = [0.0] * ranks
        for k in keys:
            sign = -1.0 if k.startswith("-") else 1.0
            k = k.lstrip("-")
            if k in t and "per_rank" in t[k]:
                values = [a + sign * b for a, b in zip(values, t[k]["per_rank"])]
        out.append((name, values))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("summaries", nargs="+")
    ap.add_argument("--labels")
    ap.add_argument("--png")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    runs = [json.load(open(p)) for p in a.summaries]
    labels = a.labels.split(",") if a.labels else [p.rsplit("/", 2)[-2] for p in a.summaries]
    for label, s in zip(labels, runs):
        groups = per_rank(s)
        work = s.get("per_rank", {}).get("work")
        print(f"{label}: {s['ranks']} ranks, wall {s['wall_seconds']:.1f} s, imbalance (work) {s.get('imbalance', float('nan')):.3f}")
        print("| rank | " + " | ".join(g for g, _ in groups) + " | work |")
        print("|---" * (len(groups) + 2) + "|")
        for r in range(s["ranks"]):
            cells = " | ".join(f"{v[r]:.2f}" for _, v in groups)
            print(f"| {r} | {cells} | {work[r] if work else '-'} |")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(1.6 + 1.1 * sum(s["ranks"] for s in runs), 4.2))
        colours = ["#4c72b0", "#55a868", "#8172b2", "#c44e52"]
        x, ticks, names = 0, [], []
        for label, s in zip(labels, runs):
            groups = per_rank(s)
            for r in range(s["ranks"]):
                bottom = 0.0
                for (name, v), c in zip(groups, colours):
                    ax.bar(x, v[r], bottom=bottom, color=c, label=name if x == 0 else None, width=0.8)
                    bottom += v[r]
                ticks.append(x)
                names.append(f"{label}\nrank {r}")
                x += 1
            x += 0.6
        ax.set_xticks(ticks)
        ax.set_xticklabels(names, fontsize=8)
        ax.set_ylabel("seconds")
        ax.set_title(a.title or "time per rank")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.png, dpi=120)
        print(f"wrote {a.png}")


if __name__ == "__main__":
    main()
