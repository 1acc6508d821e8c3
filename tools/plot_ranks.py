#!/usr/bin/python3
"""Time per rank of one or more runs, side by side (the blast seed's Fig. 15: each rank's time with
and without rebalancing), from the per-rank timers of their summary.json files: a table on stdout
and, with --png, stacked bars per rank (computation, cell search and integration, communication,
and the wait at the rebuild check's reduction; for a coupled run: the flow and coupling stages, the
DEM, and the communication with its waits).

usage: tools/plot_ranks.py RUN_A/summary.json [RUN_B/summary.json ...] [--labels A,B] [--png FILE]

The blast's work per rank at a checkpoint, on the start's partition and repartitioned there (the
`tessera balance CASE --bodies CHECKPOINT --json FILE` of a blast case), from its exact counts:

       tools/plot_ranks.py --blast-balance FILE --ranks 16 [--method metis] [--png FIGURE]

each rank's work over a macro step's sub-steps (sum_f c_f W_f[r], stacked by sub-step kind f), and
the step's time in the same units (sum_f c_f max_r W_f[r]: every sub-step waits for its busiest
rank); the gap between a rank's bar and its line is that rank's wait.
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


def substeps(f):
    """Sub-steps of kind f in a macro step (element_partition.hpp's c_f)."""
    return 1.0 if f == 0 else 2.0 ** (f - 1)


def blast_balance(a):
    report = json.load(open(a.blast_balance))
    rows = [r for r in report["table"] if r["ranks"] == a.ranks]
    if not rows or "checkpoint" not in rows[0]:
        raise SystemExit(f"plot_ranks: {a.blast_balance} has no checkpoint row for {a.ranks} ranks")
    ck = rows[0]["checkpoint"][a.method]
    if "start_partition_level_work" not in ck:
        raise SystemExit(f"plot_ranks: {a.blast_balance} predates the per-rank work (run `tessera balance` again)")
    sets = [("start's partition", ck["start_partition_level_work"]), ("repartitioned", ck["repartitioned_level_work"])]
    print(f"{report['case']}, {report['elements']} elements, {a.ranks} ranks, {a.method}, work at the checkpoint "
          "(element updates a macro step):")
    print("| partition | step (busiest ranks' sum) | mean rank | imbalance |")
    print("|---|---|---|---|")
    for label, work in sets:
        step = sum(substeps(f) * max(row) for f, row in enumerate(work))
        mean = sum(substeps(f) * sum(row) / len(row) for f, row in enumerate(work))
        print(f"| {label} | {step:.0f} | {mean:.0f} | {step / mean:.3f} |")
    if not a.png:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(13.5, 4.2), sharey=True)
    cmap = plt.get_cmap("viridis")
    for ax, (label, work) in zip(axes, sets):
        nf, p = len(work), len(work[0])
        bottom = [0.0] * p
        for f, row in enumerate(work):
            part = [substeps(f) * w for w in row]
            ax.bar(range(p), part, bottom=bottom, color=cmap(f / max(1, nf - 1)), width=0.8,
                   label=f"kind {f} ({substeps(f):g} a step)")
            bottom = [b + v for b, v in zip(bottom, part)]
        step = sum(substeps(f) * max(row) for f, row in enumerate(work))
        mean = sum(bottom) / p
        ax.axhline(step, color="k", ls="--", lw=1, label="the step (each sub-step's busiest rank)")
        ax.set_title(f"{label}: step {step / mean:.3f} x the mean rank")
        ax.set_xlabel("rank")
        ax.set_xticks(range(p))
    axes[0].set_ylabel("work a macro step (element updates)")
    handles, names = axes[1].get_legend_handles_labels()
    fig.legend(handles[::-1], names[::-1], fontsize=7, loc="center right")
    fig.suptitle(a.title or f"{report['elements']} elements at the checkpoint, {a.ranks} ranks ({a.method})")
    fig.tight_layout(rect=(0, 0, 0.83, 1))
    fig.savefig(a.png, dpi=120)
    print(f"wrote {a.png}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("summaries", nargs="*")
    ap.add_argument("--labels")
    ap.add_argument("--png")
    ap.add_argument("--title", default="")
    ap.add_argument("--blast-balance", help="a blast case's `tessera balance ... --bodies CHECKPOINT --json` file")
    ap.add_argument("--ranks", type=int, default=16)
    ap.add_argument("--method", default="metis", choices=["slabs", "balanced", "metis"])
    a = ap.parse_args()
    if a.blast_balance:
        blast_balance(a)
        return
    if not a.summaries:
        ap.error("summary.json files, or --blast-balance")
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
