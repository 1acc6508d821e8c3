#!/usr/bin/python3
"""Strong scaling of a case: runs it on a list of rank counts (here, or as Slurm jobs), then gathers
each run's summary.json into speed-up, parallel efficiency and the time per phase (the seeds' Fig.
10 / Fig. 14 / Table 3 style).

  tools/scaling.py run CASE.yaml --ranks 1,2 [--repeat 3] [--packed K] [--set key=value ...] [--out runs/scaling]
        --packed K: each 1-rank run is K copies at once, so that its per-core rate is that of a busy node
  tools/scaling.py slurm CASE.yaml --ranks 1,2,4,8,16 [--time 02:00:00] [--partition P] [--out D]
        writes D/scaling_P.sbatch per rank count and D/submit.sh (sbatch each); then `report`
  tools/scaling.py report --out D [--png FILE]
  tools/scaling.py network --out D          (mpirun -n 2; needs python3-mpi4py) this machine's MPI costs,
        t = latency + bytes / bandwidth fitted over 8 B - 1 MB for the all-gather and for the halo's
        MPI_Sendrecv (whose 14 sizes' medians the coupled model prices messages between), messages in
        flight at once, and a two-double all-reduce, in D/network.json
  tools/scaling.py iterations CASE.yaml --ranks 4,16,25,64,100 [--steps 3] [--cuts-from D/balance.json] --out D
        the Poisson's iterations per flow step on P ranks (oversubscribed: counts, not times) in
        D/iterations.json; the coupled model scales the Poisson's time and messages by them;
        --cuts-from: on the balanced cuts and grid of a `tessera balance` JSON (the model's)
  tools/scaling.py model CASE.yaml --ranks 2,4,16,64 --out D [--bodies CHECKPOINT] [--cuts balanced] [--png F] [--set ...]
        [--balance D0/balance.json]
        predicts the loop time on P ranks from D's 1-rank runs, the work per rank that `tessera balance`
        counts for P on one process, and D/network.json; where D holds measured runs on P ranks it
        prints the model's error. The blast (its levelled step), a DEM scene of spheres or discs
        whose bodies --bodies gives (the run's starting checkpoint), or a coupled case (its bed as
        --bodies; D also needs a 2-rank run, whose halo traffic per flow step the model scales;
        coupled_model below). --message-cost line: the point-to-point messages priced by the
        fitted line instead of between the measured sizes (the DEM, blast and coupled models' figures
        before 2026-12-05 were made so).

The blast's model (stability levels): every sub-step takes its busiest rank's work and ends in the
halo's exchange: each rank sends each neighbour the states of its due elements that the neighbour's
bonds read (14 doubles each); the macro step ends in one all-gather of every element. A macro step's
compute time is proportional to substep_time (the sum over sub-step kinds f, c_f of them per macro
step, of the busiest rank's work; element_partition.hpp, written by `tessera balance` per partition),
so T(P) = T(1) substep_time(P) / substep_time(1) + steps [latency_ag ceil(log2 P) + 112 N (P - 1) / P
/ bandwidth_ag + sum_f c_f (latency_sr + 112 max_r H_f,r / bandwidth_sr)], H_f,r the elements rank
r sends after a sub-step of kind f (`level_halo_sent`, at the initial levels; the contacts' pairs
across ranks come later and are not counted), with the sendrecv's latency and bandwidth: the
messages to every neighbour are in flight together, so one latency (a lower bound: the overhead of
each message, up to `halo_neighbours` of them, is not counted). T(1) is the measured 1-rank loop time: its contact work, which the partition cannot
plan, is assumed to split as the rest.

The DEM model: every step ends in an all-reduce (the list check), so the busiest rank sets the
pace. Rank r's step costs the 1-rank run's contact time times its share of the listed pairs (a pair
across a cut counted on both sides), the integration, wall forces and the rest times its share of
the bodies, and the list build and check times its share of owned plus ghost bodies
(solid/rank_load.hpp, counted from the checkpoint for the cuts a run on P ranks has). Then per
step each of the halo's swaps (two per split direction) at the sendrecv latency plus the busiest
receiver's ghosts x 72 bytes over the bandwidth, and ceil(log2 P) all-reduces (and, with free
spheres or moving meshes, ceil(log2 P) more for their loads, 6 exact sums of 69 integers each). The
work is taken
where the checkpoint has it: a scene whose work moves (a deposition) is outside the model.

The time of a run is its loop_seconds (the time-step loop, as LAMMPS' Loop time: set-up and the
final output not counted); with --repeat the median, repeats alternating over the rank counts.
Speed-up is relative to the smallest rank count P0: S(P) = P0 T(P0) / T(P), efficiency S(P) / P.
Each run's per-phase times are the mean over its ranks, and the busiest rank's (summary.json's
timers, per_rank). TESSERA names the binary (default build/bin/tessera).
"""
import argparse
import glob
import json
import math
import os
import shlex
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TESSERA = os.environ.get("TESSERA", os.path.join(ROOT, "build", "bin", "tessera"))
PHASES = [("contact computation", ["contact_forces", "wall_forces"]), ("integration", ["integrate"]),
          ("cell search", ["neighbor"]), ("communication", ["ghost_comm", "migration"]),
          ("waiting", ["reduction"]), ("flow", ["flow", "advect", "viscous", "project"]), ("output", ["output"])]


def message_time(net, nbytes, line=False):
    """One message each way between two ranks carrying nbytes: between the sizes `network` measured
    (MPI_Sendrecv; piecewise linear, made non-decreasing: a larger message never costs less), beyond
    the largest at the fitted bandwidth; or, with line (or a network.json without the samples), the
    latency-bandwidth line fitted over all sizes. The line's latency comes from the large messages'
    residuals: on this host 3.0-3.6 us against about 1 us measured up to 1 kB, and 4 us against
    7-9 us measured at 8-16 kB (docs/performance.md)."""
    lat = net.get("sendrecv_latency_s", net.get("latency_s"))
    bw = net.get("sendrecv_bandwidth_bytes_per_s", net.get("bandwidth_bytes_per_s"))
    samples = net.get("sendrecv_samples")
    if line or not samples:
        return lat + nbytes / bw
    xs = [r["bytes_each_way"] for r in samples]
    ys, top = [], 0.0
    for r in samples:
        top = max(top, r["seconds"])
        ys.append(top)
    if nbytes <= xs[0]:
        return ys[0]
    for i in range(1, len(xs)):
        if nbytes <= xs[i]:
            return ys[i - 1] + (ys[i] - ys[i - 1]) * (nbytes - xs[i - 1]) / (xs[i] - xs[i - 1])
    return ys[-1] + (nbytes - xs[-1]) / bw


def tessera_args(case, sets, out):
    args = ["run", os.path.abspath(case), "--quiet", "--output", out, "--set", "output.snapshot_interval=0"]
    for s in sets:
        args += ["--set", s]
    return args


def run(a):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    for rep in range(a.repeat):
        for p in a.ranks:
            # --packed K: the 1-rank run as K copies at once (P1_rR_cK), each core of a K-core node busy
            # as in the runs on many ranks: the per-core rate the model scales from (memory bandwidth
            # and caches are shared; docs/performance.md, 2026-12-05).
            copies = a.packed if p == 1 and a.packed > 1 else 1
            outs = [os.path.join(a.out, f"P{p}_r{rep}" + (f"_c{c}" if copies > 1 else "")) for c in range(copies)]
            if all(os.path.exists(os.path.join(out, "summary.json")) for out in outs):
                continue
            procs = []
            for out in outs:
                # Copies side by side: each mpirun would bind its rank to the first core.
                bind = ["--bind-to", "none"] if copies > 1 else []
                cmd = ["mpirun", "-n", str(p)] + bind + [TESSERA] + tessera_args(a.case, a.set, out)
                print(" ".join(shlex.quote(c) for c in cmd), flush=True)
                procs.append(subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL))
            for proc in procs:
                if proc.wait() != 0:
                    sys.exit(f"scaling: a run failed ({proc.args})")
    report(a)


def iterations(a):
    """The Poisson's CG iterations per flow step on each rank count (the multigrid's levels follow the
    ranks' blocks, so they change with P): a few flow steps on P ranks, oversubscribed where P exceeds
    the cores (their times mean nothing; their counts do), into D/iterations.json. With --on-one each P
    runs on one process with the multigrid's levels laid out as on P ranks (the balance's grid and cuts,
    `fluid.poisson.multigrid.levels_as_on`): the V-cycle's arithmetic is P ranks', so are the counts
    (test CellMultigrid.LevelsLaidOutAsOnAnotherGridTakeItsIterations), for any P in one process's
    memory."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    path = os.path.join(a.out, "iterations.json")
    table = json.load(open(path)) if os.path.exists(path) else {}
    balanced = {}
    if a.cuts_from:
        balanced = {row["ranks"]: row for row in json.load(open(a.cuts_from))["table"]}
        missing = [p for p in a.ranks if p > 1 and p not in balanced]
        if missing:
            sys.exit(f"scaling iterations: {a.cuts_from} has no cuts for {missing} ranks")
    elif a.on_one:
        sys.exit("scaling iterations: --on-one takes each P's grid and cuts from --cuts-from")
    for p in sorted(set([1] + a.ranks)):
        out = os.path.join(a.out, f"iterations_P{p}")
        sets = a.set + [f"run.max_steps={a.steps}", "output.checkpoint_interval=0"]
        procs = p
        if p > 1 and balanced:
            row = balanced[p]
            grid = "[%d,%d,%d]" % tuple(row["grid"])
            cuts = "{" + ", ".join(f"{'xyz'[d]}: [{', '.join(repr(c) for c in row['cuts'][d])}]"
                                   for d in range(3) if row["cuts"][d]) + "}"
            if a.on_one:
                procs = 1
                sets += [f"fluid.poisson.multigrid.levels_as_on={{process_grid: {grid}, cuts: {cuts}}}"]
            else:
                sets += ["domain.process_grid=" + grid, "domain.cuts=" + cuts]
        cmd = ["mpirun", "-n", str(procs), "--bind-to", "none", TESSERA] + tessera_args(a.case, sets, out)
        print(" ".join(shlex.quote(c) for c in cmd), flush=True)
        subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
        s = json.load(open(os.path.join(out, "summary.json")))
        table[str(p)] = {"iterations_per_step": s["poisson"]["iterations_per_step"],
                         "cuts": "balanced" if p > 1 and balanced else "equal",
                         "coarsest_cells": s["poisson"].get("coarsest_cells", 0),
                         "levels": s["poisson"].get("levels", 0),
                         "gathered_levels": s["poisson"].get("gathered_levels", 0),
                         "two_layer_levels": s["poisson"].get("two_layer_levels", 0),
                         "exchanges_per_cycle": s["poisson"].get("exchanges_per_cycle", 0),
                         "process_grid": s.get("process_grid"), "steps": s["steps"]}
        if procs != p:  # one process: the levels are P ranks', their halos and gathers are not run
            table[str(p)].update({"process_grid": balanced[p]["grid"], "on_one_process": True,
                                  "gathered_levels": None, "two_layer_levels": None, "exchanges_per_cycle": None})
        row = table[str(p)]
        if procs != p:
            print(f"{p} ranks {row['process_grid']} laid out on one process: {row['iterations_per_step']:.2f} "
                  f"iterations a step, {row['levels']} levels, the coarsest {row['coarsest_cells']} cells", flush=True)
        else:
            print(f"{p} ranks {s.get('process_grid')}: {row['iterations_per_step']:.2f} iterations a step, "
                  f"{row['levels']} levels ({row['gathered_levels']} gathered onto fewer ranks, "
                  f"{row['two_layer_levels']} with two ghost layers; "
                  f"{row['exchanges_per_cycle']:.1f} exchanges a cycle), "
                  f"the coarsest {row['coarsest_cells']} cells", flush=True)
    os.makedirs(a.out, exist_ok=True)
    with open(path, "w") as f:
        json.dump(table, f, indent=1)


def slurm(a):
    os.makedirs(a.out, exist_ok=True)
    scripts = []
    for p in a.ranks:
        out = os.path.abspath(os.path.join(a.out, f"P{p}_r0"))
        line = " ".join(shlex.quote(x) for x in tessera_args(a.case, a.set, out))
        path = os.path.join(a.out, f"scaling_{p}.sbatch")
        partition = f"#SBATCH --partition={a.partition}\n" if a.partition else ""
        with open(path, "w") as f:
            f.write(f"""#!/bin/bash
#SBATCH --job-name=scaling-{p}
#SBATCH --ntasks={p}
#SBATCH --time={a.time}
{partition}#SBATCH --output={os.path.abspath(a.out)}/slurm-{p}-%j.out
# tools/scaling.py slurm: one run of {a.case} on {p} ranks; afterwards tools/scaling.py report --out {a.out}
cd {ROOT}
srun {TESSERA} {line}
""")
        scripts.append(path)
    with open(os.path.join(a.out, "submit.sh"), "w") as f:
        f.write("#!/bin/bash\n" + "".join(f"sbatch {s}\n" for s in scripts))
    os.chmod(os.path.join(a.out, "submit.sh"), 0o755)
    print(f"scaling: {len(scripts)} job scripts in {a.out}; submit with {os.path.join(a.out, 'submit.sh')}")


def load(out):
    runs = {}
    for path in sorted(glob.glob(os.path.join(out, "P*_r*", "summary.json"))):
        s = json.load(open(path))
        runs.setdefault(s["ranks"], []).append(s)
    return runs


def phase_times(s):
    t = s["timers"]
    mean, busiest = {}, {}
    for name, keys in PHASES:
        present = [k for k in keys if k in t]
        if not present:
            continue
        per_rank = [sum(t[k].get("per_rank", [t[k]["avg"]] * s["ranks"])[r] for k in present) for r in range(s["ranks"])]
        mean[name] = sum(per_rank) / len(per_rank)
        busiest[name] = max(per_rank)
    return mean, busiest


def report(a):
    runs = load(a.out)
    if not runs:
        sys.exit(f"scaling: no finished runs in {a.out}")
    ps = sorted(runs)
    times = {p: statistics.median(s["loop_seconds"] for s in runs[p]) for p in ps}
    spread = {p: (min(s["loop_seconds"] for s in runs[p]), max(s["loop_seconds"] for s in runs[p])) for p in ps}
    p0 = ps[0]
    print(f"| ranks | grid | loop time, median (min-max) | speed-up | efficiency | imbalance | runs |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for p in ps:
        s = runs[p][0]
        speedup = p0 * times[p0] / times[p]
        rows.append((p, speedup, speedup / p))
        grid = "x".join(str(g) for g in s.get("process_grid", []))
        imb = s.get("imbalance")
        print(f"| {p} | {grid} | {times[p]:.2f} s ({spread[p][0]:.2f}-{spread[p][1]:.2f}) | {speedup:.2f} | "
              f"{speedup / p:.2f} | {'-' if imb is None else f'{imb:.3f}'} | {len(runs[p])} |")
    print("\nper phase, mean over the ranks / busiest rank (s), first run of each rank count:")
    names = [n for n, _ in PHASES]
    print("| ranks | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for p in ps:
        mean, busiest = phase_times(runs[p][0])
        print(f"| {p} | " + " | ".join(f"{mean[n]:.2f} / {busiest[n]:.2f}" if n in mean else "-" for n in names) + " |")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 3, figsize=(13, 4))
        ax[0].plot(ps, [r[1] for r in rows], "o-", label="measured")
        ax[0].plot(ps, [p / p0 for p in ps], "k--", label="ideal")
        ax[0].set_xlabel("ranks"), ax[0].set_ylabel(f"speed-up (against {p0} rank{'s' if p0 > 1 else ''})")
        ax[0].legend()
        ax[1].plot(ps, [r[2] * p0 for r in rows], "o-")
        ax[1].set_ylim(0, 1.1), ax[1].set_xlabel("ranks"), ax[1].set_ylabel("parallel efficiency")
        bottom = [0.0] * len(ps)
        for n in names:
            v = [phase_times(runs[p][0])[0].get(n, 0.0) for p in ps]
            if any(v):
                ax[2].bar([str(p) for p in ps], v, bottom=bottom, label=n)
                bottom = [b + x for b, x in zip(bottom, v)]
        ax[2].set_xlabel("ranks"), ax[2].set_ylabel("seconds per rank (mean)"), ax[2].legend(fontsize=7)
        fig.suptitle(os.path.basename(runs[p0][0].get("case", {}).get("scene", "")) + f" scaling ({a.out})")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)
        print(f"wrote {a.png}")


def network(a):
    """The all-gather's cost between 2 ranks: run under mpirun by itself (`network --measure`)."""
    if not a.measure:
        try:
            import mpi4py  # noqa: F401
        except ImportError:
            sys.exit("scaling network: needs mpi4py (apt-get install python3-mpi4py)")
        os.makedirs(a.out, exist_ok=True)
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1")
        subprocess.run(["mpirun", "-n", "2", sys.executable, os.path.abspath(__file__), "network", "--measure",
                        "--out", a.out], check=True, env=env)
        print(open(os.path.join(a.out, "network.json")).read())
        return
    from mpi4py import MPI
    import numpy as np
    comm = MPI.COMM_WORLD
    rows = []
    for size in (1, 16, 128, 1024, 8192, 65536, 131072):  # doubles per rank
        mine = np.zeros(size)
        everything = np.zeros(size * comm.size)
        counts = [size] * comm.size
        for _ in range(20):  # warm-up
            comm.Allgatherv(mine, [everything, counts])
        reps = max(20, 20000 // size)
        comm.Barrier()
        t = MPI.Wtime()
        for _ in range(reps):
            comm.Allgatherv(mine, [everything, counts])
        dt = (MPI.Wtime() - t) / reps
        rows.append((8.0 * size * (comm.size - 1), comm.allreduce(dt, op=MPI.MAX)))
    # The DEM halo's swap: one MPI_Sendrecv with the neighbour (each rank sends and receives size
    # doubles), as Halo::forward. Sizes from 8 bytes to 1 MB, close enough together to follow the
    # protocol changes (this host: about 1 us to 1 kB, then a jump to 6-9 us from 8 to 64 kB): the
    # scaling model prices each message by its size between these samples. Five rounds over all
    # sizes, each size's median.
    sizes = (1, 16, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384, 32768, 65536, 131072)
    times = {size: [] for size in sizes}
    other = (comm.rank + 1) % comm.size
    for _ in range(5):
        for size in sizes:
            out, back = np.zeros(size), np.zeros(size)
            for _ in range(20):
                comm.Sendrecv(out, dest=other, recvbuf=back, source=other)
            reps = max(20, 20000 // size)
            comm.Barrier()
            t = MPI.Wtime()
            for _ in range(reps):
                comm.Sendrecv(out, dest=other, recvbuf=back, source=other)
            times[size].append(comm.allreduce((MPI.Wtime() - t) / reps, op=MPI.MAX))
    swaps = [(8.0 * size, float(np.median(times[size]))) for size in sizes]
    # Messages in flight together (a cell halo's round, fluid/cell_halo.hpp: one message to each
    # neighbour rank): here k small messages (8 doubles) each way at once to the other rank, so that
    # t(k) = t(1) + (k - 1) overhead gives each further message's cost.
    flights = []
    for k in (1, 2, 4, 8, 16, 26):
        outs, backs = [np.zeros(8) for _ in range(k)], [np.zeros(8) for _ in range(k)]

        def exchange():
            reqs = [comm.Irecv(backs[i], source=other, tag=i) for i in range(k)]
            reqs += [comm.Isend(outs[i], dest=other, tag=i) for i in range(k)]
            MPI.Request.Waitall(reqs)
        for _ in range(50):
            exchange()
        comm.Barrier()
        t = MPI.Wtime()
        for _ in range(2000):
            exchange()
        flights.append((k, comm.allreduce((MPI.Wtime() - t) / 2000, op=MPI.MAX)))
    # The DEM's per-step check (two doubles, MPI_MAX).
    two = np.zeros(2)
    for _ in range(100):
        comm.Allreduce(MPI.IN_PLACE, two, op=MPI.MAX)
    comm.Barrier()
    t = MPI.Wtime()
    for _ in range(5000):
        comm.Allreduce(MPI.IN_PLACE, two, op=MPI.MAX)
    allreduce = comm.allreduce((MPI.Wtime() - t) / 5000, op=MPI.MAX)
    if comm.rank == 0:
        def fit(samples):
            slope, intercept = np.polyfit(np.array([r[0] for r in samples]), np.array([r[1] for r in samples]), 1)
            return float(intercept), float(1 / slope)
        lat, bw = fit(rows)
        p2p_lat, p2p_bw = fit(swaps)
        overhead = float(np.polyfit(np.array([r[0] for r in flights]), np.array([r[1] for r in flights]), 1)[0])
        json.dump({"message_overhead_s": overhead,
                   "in_flight_samples": [{"messages_each_way": r[0], "seconds": r[1]} for r in flights],"ranks": comm.size, "latency_s": lat, "bandwidth_bytes_per_s": bw,
                   "sendrecv_latency_s": p2p_lat, "sendrecv_bandwidth_bytes_per_s": p2p_bw,
                   "allreduce_s": allreduce,
                   "samples": [{"bytes_received": r[0], "seconds": r[1]} for r in rows],
                   "sendrecv_samples": [{"bytes_each_way": r[0], "seconds": r[1]} for r in swaps]},
                  open(os.path.join(a.out, "network.json"), "w"), indent=1)


def model(a):
    runs = load(a.out)
    if 1 not in runs:
        sys.exit(f"scaling model: no 1-rank run in {a.out} (tools/scaling.py run CASE --ranks 1,2 --out {a.out})")
    net_path = os.path.join(a.out, "network.json")
    if not os.path.exists(net_path):
        sys.exit(f"scaling model: no {net_path} (tools/scaling.py network --out {a.out})")
    net = json.load(open(net_path))
    ranks = sorted(set([1] + a.ranks))
    if "coupling" in runs[1][0] and not any(x.startswith("coupling.substeps=") for x in a.set):
        # A coupled case's bodies weigh by the DEM sub-steps of a flow step: the 1-rank run's.
        a.set.append(f"coupling.substeps={max(1, round(runs[1][0]['coupling']['substeps_per_flow_step']))}")
    bal = os.path.join(a.out, "balance.json")
    if a.balance:  # an earlier `tessera balance` of the same case, bodies and rank counts
        b = json.load(open(a.balance))
        missing = [p for p in ranks if p not in [row["ranks"] for row in b["table"]]]
        if missing:
            sys.exit(f"scaling model: {a.balance} has no rows for {missing} ranks")
        b["table"] = [row for row in b["table"] if row["ranks"] in ranks]
    else:
        cmd = [TESSERA, "balance", os.path.abspath(a.case), "--ranks", ",".join(map(str, ranks)), "--json", bal]
        if a.bodies:
            cmd += ["--bodies", os.path.abspath(a.bodies)]
        for x in a.set:
            cmd += ["--set", x]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        b = json.load(open(bal))
    if "partition" in b:
        rows = blast_model(a, b, runs, net)
    elif b.get("cells"):
        rows = coupled_model(a, b, runs, net)
    else:
        rows = dem_model(a, b, runs, net)
    print("| ranks | compute (s) | exchange (s) | predicted loop time (s) | speed-up | efficiency | measured (s) | model error |")
    print("|---|---|---|---|---|---|---|---|")
    t1 = rows[0]["predicted"]
    for r in rows:
        p, t, measured = r["ranks"], r["predicted"], r["measured"]
        err = "-" if measured is None else f"{100 * (t - measured) / measured:+.1f} %"
        print(f"| {p} | {r['compute']:.2f} | {r['exchange']:.2f} | {t:.2f} | {t1 / t:.2f} | {t1 / t / p:.2f} | "
              f"{'-' if measured is None else f'{measured:.2f}'} | {err} |")
    json.dump({"case": b["case"], "rows": rows}, open(os.path.join(a.out, "model.json"), "w"), indent=1)
    if a.png:
        plot_model(a, rows)


def plot_model(a, rows):
    """Predicted speed-up and the time per step's compute and exchange, with the measured points."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ps = [r["ranks"] for r in rows]
    t1 = rows[0]["predicted"]
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    ax[0].loglog(ps, [t1 / r["predicted"] for r in rows], "o-", label="predicted")
    measured = [(r["ranks"], t1 / r["measured"]) for r in rows if r["measured"]]
    if measured:
        ax[0].loglog(*zip(*measured), "s", ms=9, mfc="none", label="measured (median)")
    ax[0].loglog(ps, ps, "k--", lw=0.8, label="ideal")
    ax[0].set_xlabel("ranks"), ax[0].set_ylabel("speed-up against 1 rank"), ax[0].legend()
    labels = [str(p) for p in ps]
    # Core-seconds (P x loop time): flat when the scaling is ideal.
    if all("stages" in r for r in rows):  # a coupled step's stages, each its busiest rank's
        bottom = [0.0] * len(rows)
        for name, text in (("cells", "flow and cell-wise coupling"), ("bodies", "solid fraction and fluid force"),
                           ("dem", "DEM sub-steps")):
            h = [p * r["stages"][name] for p, r in zip(ps, rows)]
            ax[1].bar(labels, h, bottom=bottom, label=text + " (busiest rank)")
            bottom = [b + x for b, x in zip(bottom, h)]
    else:
        ax[1].bar(labels, [p * r["compute"] for p, r in zip(ps, rows)], label="compute (busiest rank)")
    ax[1].bar(labels, [p * r["exchange"] for p, r in zip(ps, rows)], bottom=[p * r["compute"] for p, r in zip(ps, rows)],
              label="exchange")
    if measured:
        ax[1].plot([labels[ps.index(p)] for p, _ in measured], [p * t1 / s for p, s in measured], "s", ms=9,
                   mfc="none", label="measured (median)")
    ax[1].set_xlabel("ranks"), ax[1].set_ylabel("ranks x predicted loop time (core-s)")
    ax[1].legend(fontsize=8)
    fig.suptitle(f"scaling model: {os.path.basename(a.case)} ({a.out})")
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print(f"wrote {a.png}")


def median_loop(runs, p):
    return statistics.median(s["loop_seconds"] for s in runs[p]) if p in runs else None


def blast_model(a, b, runs, net):
    """The blast's levelled step: every sub-step waits for its busiest rank, then sends each neighbour
    the due elements its bonds read (the halo); the macro step ends in one all-gather of every element."""
    t1 = median_loop(runs, 1)
    steps = runs[1][0]["steps"]
    how, n_f = b["partition"], b["level_elements"]
    sr_lat = net.get("sendrecv_latency_s", net["latency_s"])
    sr_bw = net.get("sendrecv_bandwidth_bytes_per_s", net["bandwidth_bytes_per_s"])

    def c(f):
        return 1.0 if f == 0 else 2.0 ** (f - 1)

    base = b["table"][0][how]["substep_time"]
    print(f"model: {b['case']}, partition {how}, {b['elements']} elements, {len(n_f)} levels, {steps} macro steps; "
          f"1 rank {t1:.2f} s; all-gather latency {1e6 * net['latency_s']:.1f} us, "
          f"{net['bandwidth_bytes_per_s'] / 1e9:.2f} GB/s; halo {1e6 * sr_lat:.1f} us, {sr_bw / 1e9:.2f} GB/s")
    rows = []
    for row in b["table"]:
        p = row["ranks"]
        part = row[how]
        compute = t1 * part["substep_time"] / base
        exchange = 0.0
        if p > 1:
            hops = math.ceil(math.log2(p))
            gather = hops * net["latency_s"] + 112.0 * n_f[0] * (p - 1) / p / net["bandwidth_bytes_per_s"]
            # 14 doubles an element; every rank waits for the slowest. The messages to all neighbours
            # are in flight together (MPI_Isend/Irecv): one latency, then the busiest rank's bytes (a
            # lower bound: per-message overheads not counted).
            halo = sum(c(f) * message_time(net, 112.0 * max(sent), a.message_cost == "line")
                       for f, sent in enumerate(part["level_halo_sent"]))
            exchange = steps * (gather + halo)
        rows.append({"ranks": p, "compute": compute, "exchange": exchange, "predicted": compute + exchange,
                     "measured": median_loop(runs, p)})
    return rows


def dem_model(a, b, runs, net):
    """A DEM step (sphere or disc bodies) on P ranks: each rank's work from its counts in
    `tessera balance --bodies` (solid/rank_load.hpp), costed by the 1-rank run's phases, the slowest
    rank setting the pace (every step ends in an all-reduce); then the halo's swaps and the
    all-reduce with the latency and bandwidth of network.json."""
    if "sendrecv_latency_s" not in net:
        sys.exit("scaling model: network.json predates the point-to-point measurement; run `network` again")
    one = runs[1][0]
    t1, steps = median_loop(runs, 1), one["steps"]

    def avg(*names):  # the phases' shares of the loop, averaged over the 1-rank runs, times the median
        return t1 * statistics.mean(sum(s["timers"][n]["avg"] for n in names if n in s["timers"]) / s["loop_seconds"]
                                    for s in runs[1])

    # Per-step work at one rank, by what it scales with.
    contact = avg("contact_forces")
    per_body = avg("integrate", "wall_forces")
    per_local = avg("neighbor", "migration", "ghost_comm")  # owned and ghost bodies: list build, check
    rest = max(0.0, t1 - contact - per_body - per_local)  # output, the moving walls' kinematics, the loop
    # Free spheres and moving meshes (the ball, the club) are kept whole on every rank: their loads
    # are all-gathered every step.
    replicated = len(one.get("free_spheres", [])) + len(one.get("mesh_walls", []))  # loads summed every step
    row1 = b["table"][0]
    cuts = "load_balanced" if a.cuts == "balanced" else "load_equal"
    B, C = float(b["count"]), row1[cuts]["total_pairs"]
    lat, bw, red = net["sendrecv_latency_s"], net["sendrecv_bandwidth_bytes_per_s"], net["allreduce_s"]
    if "message_overhead_s" not in net:
        print("scaling model: network.json predates the messages-in-flight measurement; each further message "
              "of an exchange counted as free (run `network` again)")
    overhead = net.get("message_overhead_s", 0.0)
    print(f"model: {b['case']}, {b['count']} bodies, {C:.0f} listed pairs (skin {b['skin']:.3g} m), {steps} steps, "
          f"{a.cuts} cuts; 1 rank {t1:.2f} s = contacts {contact:.2f} + per body {per_body:.2f} + lists "
          f"{per_local:.2f} + rest {rest:.2f}; swap {1e6 * lat:.2f} us + bytes / {bw / 1e9:.2f} GB/s, "
          f"all-reduce {1e6 * red:.2f} us (2 ranks)")
    rows = []
    for row in b["table"]:
        p, dims, load = row["ranks"], row["grid"], row[cuts]
        compute = max(contact * load["pairs"][r] / C + (per_body + rest) * load["bodies"][r] / B +
                      per_local * (load["bodies"][r] + load["ghosts"][r]) / B for r in range(p))
        exchange = 0.0
        if p > 1:
            per_step = math.ceil(math.log2(p)) * red
            if replicated:  # the replicated bodies' loads: one all-reduce of exact sums (ReplicatedLoads::sum)
                per_step += math.ceil(math.log2(p)) * (red + replicated * 6 * 69 * 8 / bw)
            for d in range(3):
                if dims[d] > 1:
                    for side in range(2):
                        most = max(load["recv"][r][2 * d + side] for r in range(p))
                        per_step += message_time(net, 72.0 * most, a.message_cost == "line")  # x, v, omega a ghost
            exchange = steps * per_step
        rows.append({"ranks": p, "grid": dims, "compute": compute, "exchange": exchange,
                     "predicted": compute + exchange, "measured": median_loop(runs, p),
                     "imbalance": max(load["pairs"]) * p / sum(load["pairs"])})
    return rows


def coupled_model(a, b, runs, net):
    """A coupled flow step on P ranks: its stages end in collective waits (the Poisson's reductions,
    the sub-steps' list checks, the bodies' sums), so each stage takes its busiest rank. Per rank, the
    flow's and the cell-wise coupling stages scale with its cells, the DEM sub-steps as dem_model's
    step (pairs, bodies, owned plus ghost bodies, from `tessera balance`), the solid fraction with the
    time its lay-outs take when `tessera balance` does them on one core (owned bodies and the ghosts
    whose nodes reach its cells, over its cells: a ghost's sliver costs less than a whole body) and
    the fluid force with the cells they report (an older `tessera balance`: both per laid-out body);
    each costed by the 1-rank run's timers. Then the
    exchanges: the field halos (their exchanges per flow step, and bytes per face cell, from the
    2-rank run's per-rank traffic; at P each exchange pays per split direction one message of the
    busiest rank's face's bytes, priced by its size (message_time), and network.json's overhead for
    the second side's); the multigrid's, level by level where `tessera balance` laid out its levels
    at P (fluid/multigrid_plan.hpp: each level's exchanges a V-cycle, layers and faces, its gathers,
    the coarsest level's all-gather; V-cycles a flow step from the 2-rank run), else scaled from the
    2-rank run's as the field's (below); the Poisson's reductions per Krylov
    iteration (2, or 3 in runs before CG's merged inner products), and per DEM sub-step dem_model's swaps and list check, plus 6 swaps of the bodies' sums
    per flow step (C3's loads, C4a's sums and velocities, C7's moves, the ghosts' refresh). Where
    D/iterations.json counts the Poisson's iterations on P ranks, the Poisson's time, its reductions
    and the multigrid's exchanges scale by their ratio to 1 rank's (and by the exchanges a V-cycle at P
    over the 2-rank run's, where both summaries count them: levels with two ghost layers take half), each cycle's coarsest-level
    LU adds an all-gather of that level, and each level gathered onto fewer ranks two point-to-point
    latencies a cycle (its parts in, their corrections out)."""
    if "sendrecv_latency_s" not in net:
        sys.exit("scaling model: network.json predates the point-to-point measurement; run `network` again")
    if 2 not in runs:
        sys.exit("scaling model: a coupled case needs a 2-rank run too (its halo traffic per flow step)")
    one, two = runs[1][0], runs[2][0]
    t1, steps = median_loop(runs, 1), one["steps"]

    def avg(*names):
        return t1 * statistics.mean(sum(s["timers"][n]["avg"] for n in names if n in s["timers"]) / s["loop_seconds"]
                                    for s in runs[1])

    L = one["coupling"]["substeps_per_flow_step"]
    flow = avg("flow")
    poisson = avg("flow/poisson")
    # The Poisson's iterations at P against 1 rank (`iterations`: the multigrid's levels follow the
    # blocks); at a P not counted, the largest counted P below it (a lower bound).
    it_path = os.path.join(a.out, "iterations.json")
    counted = {int(k): v for k, v in json.load(open(it_path)).items()} if os.path.exists(it_path) else {}

    def iteration_ratio(p):
        below = [q for q in counted if q <= p]
        if 1 not in counted or not below:
            return 1.0, None
        q = max(below)
        return counted[q]["iterations_per_step"] / counted[1]["iterations_per_step"], counted[q]
    cellwise = avg("pore_liquid", "correction")
    bodywise = avg("solid_fraction", "fluid_force")
    solid, force = avg("solid_fraction"), avg("fluid_force")
    contact = avg("dem/contact_forces")
    per_body = avg("dem/integrate", "dem/wall_forces")
    per_list = avg("dem/neighbor")
    per_local = avg("dem/migration", "dem/ghost_comm")
    # The DEM's phase timers also count its work outside the sub-steps stage (the ghosts' refresh and
    # lists the coupling's stages ask for, counted there too): scaled to the stage's own time.
    dem_busy = avg("dem_substeps") - avg("dem/reduction")
    scale = min(1.0, dem_busy / max(1e-30, contact + per_body + per_list + per_local))
    contact, per_body, per_list, per_local = scale * contact, scale * per_body, scale * per_list, scale * per_local
    dem_rest = max(0.0, dem_busy - contact - per_body - per_list - per_local)
    rest = max(0.0, t1 - flow - cellwise - bodywise - avg("dem_substeps"))
    cuts = "balanced" if a.cuts == "balanced" else "equal"
    row1 = b["table"][0]
    N, B, C = float(b["cells"]), float(b["count"]), row1["load_" + cuts]["total_pairs"]
    # The list bins the owned elements and the ghosts' within reach of the sub-box (theory T5b), when
    # `tessera balance` counted them; else it is priced per owned plus ghost body.
    E = sum(row1["load_" + cuts].get("owned_elements", [0.0]))
    # Better: the elements each rank's whole listing meets (`list_tests`, theory T5c: a ghost meets
    # the owned ones only), made by `tessera balance` for each rank; the list priced by them against
    # 1 rank's (its relists taken to scale as its whole listing does).
    T = sum(row1["load_" + cuts].get("list_tests", [0.0]))
    # The lay-outs each rank makes, done and timed by `tessera balance` on one core
    # (coupling/layout_cost.hpp): the solid fraction priced by their time, the fluid force by the
    # cells they report, each against 1 rank's.
    layout1 = row1["load_" + cuts].get("layout")
    # The 2-rank run's traffic: exchanges per flow step (one neighbour: a message an exchange) and
    # bytes per cell of the face between the two ranks.
    split = [d for d in range(3) if two["process_grid"][d] > 1]
    if len(split) != 1:
        sys.exit("scaling model: the 2-rank run must be split along one direction")
    grid = [int(row1["cell_slabs_" + cuts][d][0]) for d in range(3)]  # one rank: the whole grid
    cells2 = [n // (2 if d == split[0] else 1) for d, n in enumerate(grid)]
    face2 = cells2[(split[0] + 1) % 3] * cells2[(split[0] + 2) % 3]
    pr = two["per_rank"]
    msgs = {k: max(pr[k + "_halo_messages"]) / two["steps"] for k in ("field", "multigrid")}
    per_face = {k: max(pr[k + "_halo_bytes"]) / max(1, max(pr[k + "_halo_messages"])) / face2
                for k in ("field", "multigrid")}
    iters = one["poisson"]["iterations_per_step"]
    lat, red = net["sendrecv_latency_s"], net["allreduce_s"]
    if "message_overhead_s" not in net:
        print("scaling model: network.json predates the messages-in-flight measurement; each further message "
              "of an exchange counted as free (run `network` again)")
    overhead = net.get("message_overhead_s", 0.0)
    line = a.message_cost == "line"
    print(f"model: {b['case']}, {int(N)} cells, {b['count']} bodies, {C:.0f} listed pairs, {steps} flow steps of "
          f"{L:.1f} sub-steps; 1 rank {t1:.2f} s = flow {flow:.2f} + cells' coupling {cellwise:.2f} + bodies' "
          f"coupling {bodywise:.2f} + DEM {contact + per_body + per_list + per_local + dem_rest:.2f} + rest {rest:.2f}; per flow "
          f"step {msgs['field']:.1f} field and {msgs['multigrid']:.1f} multigrid exchanges, "
          f"{per_face['field']:.1f} and {per_face['multigrid']:.1f} B per face cell; {iters:.1f} Krylov iterations")
    rows = []
    for row in b["table"]:
        p, dims, load = row["ranks"], row["grid"], row["load_" + cuts]
        slabs = row["cell_slabs_" + cuts]
        cw = b["cell_weight"]
        cells = [c / cw for c in row["cell_work_" + cuts]]
        local = [load["bodies"][r] + load["ghosts"][r] for r in range(p)]
        laid = load.get("laid_out", local)
        if T > 0 and "list_tests" in load:  # the elements each rank's whole listing meets (T5c)
            listed = [load["list_tests"][r] / T * B for r in range(p)]
        elif E > 0 and "listed_ghost_elements" in load:
            listed = [(load["owned_elements"][r] + load["listed_ghost_elements"][r]) / E * B for r in range(p)]
        else:
            listed = local
        ratio, count = iteration_ratio(p)
        lay = load.get("layout")
        if layout1 and lay:
            S1, K1 = sum(layout1["seconds"]), sum(layout1["cells"])
            body_stage = [solid * lay["seconds"][r] / S1 + force * lay["cells"][r] / K1 for r in range(p)]
        else:
            body_stage = [bodywise * laid[r] / B for r in range(p)]
        stages = {"cells": max((flow + (ratio - 1) * poisson + cellwise + rest) * cells[r] / N for r in range(p)),
                  "bodies": max(body_stage),
                  "dem": max(contact * load["pairs"][r] / C + (per_body + dem_rest) * load["bodies"][r] / B +
                             per_list * listed[r] / B + per_local * local[r] / B for r in range(p))}
        compute = sum(stages.values())
        exchange = 0.0
        if p > 1:
            # The busiest rank's face along each split direction (cells of the other two directions).
            face = {d: max(slabs[(d + 1) % 3][i] * slabs[(d + 2) % 3][j] for i in range(dims[(d + 1) % 3])
                           for j in range(dims[(d + 2) % 3])) for d in range(3) if dims[d] > 1}
            # An exchange (fluid/cell_halo.hpp) goes direction by direction (the box halos: the
            # fields', the multigrid's two-layer levels; its one-layer levels send all faces in one
            # round, priced the same here, an upper bound): per split direction one latency, the
            # overhead of its second message (network.json, messages in flight), and the bytes of
            # the busiest rank's two faces.
            sides = {d: min(2, dims[d] - 1) for d in face}
            # Each message priced by its size (message_time): an exchange's bytes along d are the
            # per-face-cell bytes of the 2-rank run times the busiest rank's face, over its sides.
            per_exchange = {k: sum(message_time(net, per_face[k] * f, line) + (sides[d] - 1) * overhead
                                   for d, f in face.items()) for k in ("field", "multigrid")}
            plan = row.get("multigrid_" + cuts)
            # The Krylov's reductions an iteration: 2 with CG's merged inner products (summary's
            # poisson.reductions_per_iteration, since 2026-12-05), 3 before (runs that lack the key).
            per_iteration = two["poisson"].get("reductions_per_iteration", 3)
            reductions = per_iteration * iters * ratio * math.ceil(math.log2(p)) * red
            if plan and two["poisson"].get("exchanges_per_cycle"):
                # The multigrid's levels at P (fluid/multigrid_plan.hpp, laid out by `tessera
                # balance` on these cuts): each level's exchanges a V-cycle, each exchange along
                # each split direction a message of its layers' cells (8 bytes each) to each side,
                # the second side's at the in-flight overhead; a gathered level's parts in and their
                # corrections out, the owner's further parts at the overhead; the coarsest level's
                # right-hand side all-gathered for its LU. V-cycles a flow step: the 2-rank run's
                # (its multigrid exchanges over its exchanges a cycle) times the iterations' ratio.
                cycles = msgs["multigrid"] / two["poisson"]["exchanges_per_cycle"] * ratio
                cycle_seconds = 0.0
                for lv in plan:
                    lsides = {d: min(2, lv["procs"][d] - 1) for d in range(3) if lv["procs"][d] > 1}
                    exch = sum(message_time(net, 8.0 * lv["layers"] * lv["face_cells"][d], line) +
                               (lsides[d] - 1) * overhead for d in lsides)
                    cycle_seconds += lv["exchanges_per_cycle"] * exch
                    if lv["gathered"]:
                        cycle_seconds += 2 * (message_time(net, 8.0 * lv["part_cells"], line) +
                                              (lv["parts_per_owner"] - 2) * overhead)
                last = plan[-1]
                coarsest = last["cells"][0] * last["cells"][1] * last["cells"][2]
                owners = last["procs"][0] * last["procs"][1] * last["procs"][2]
                if owners > 1 and "latency_s" in net:
                    cycle_seconds += (math.ceil(math.log2(owners)) * net["latency_s"] +
                                      8.0 * coarsest / net["bandwidth_bytes_per_s"])
                halo = msgs["field"] * per_exchange["field"] + cycles * cycle_seconds
                per_cycle = sum(lv["exchanges_per_cycle"] for lv in plan) / two["poisson"]["exchanges_per_cycle"]
            else:
                # The multigrid's exchanges scale with the iterations and with its exchanges a cycle
                # (two ghost layers on a level halve them; which levels have two depends on P).
                per_cycle = 1.0
                if count and count.get("exchanges_per_cycle") and two["poisson"].get("exchanges_per_cycle"):
                    per_cycle = count["exchanges_per_cycle"] / two["poisson"]["exchanges_per_cycle"]
                halo = sum(msgs[k] * (ratio * per_cycle if k == "multigrid" else 1.0) * per_exchange[k]
                           for k in ("field", "multigrid"))
                if count and count.get("coarsest_cells") and "latency_s" in net:
                    # The coarsest level's LU on every rank: one all-gather of its right-hand side a cycle.
                    gather = math.ceil(math.log2(p)) * net["latency_s"] + 8.0 * count["coarsest_cells"] / net["bandwidth_bytes_per_s"]
                    reductions += (iters * ratio + 1) * gather
                if count:
                    reductions += iters * ratio * 2 * (count.get("gathered_levels") or 0) * lat
            swaps = sum(2 * message_time(net, 72.0 * max(load["recv"][r][2 * d + s] for r in range(p) for s in range(2)), line)
                        for d in face)
            dem = L * (math.ceil(math.log2(p)) * red + swaps) + 6 * swaps
            exchange = steps * (halo + reductions + dem)
            parts = {"halo": steps * halo, "reductions": steps * reductions, "dem": steps * dem}
        rows.append({"ranks": p, "grid": dims, "compute": compute, "exchange": exchange, "stages": stages,
                     "exchange_parts": parts if p > 1 else {},
                     "predicted": compute + exchange, "measured": median_loop(runs, p), "iteration_ratio": ratio,
                     "exchanges_per_cycle_ratio": per_cycle if p > 1 else 1.0,
                     "iterations_from": None if count is None else count.get("process_grid")})
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="mode", required=True)
    for mode in ("run", "slurm"):
        p = sub.add_parser(mode)
        p.add_argument("case")
        p.add_argument("--ranks", type=lambda s: [int(x) for x in s.split(",")], required=True)
        p.add_argument("--set", action="append", default=[])
        p.add_argument("--out", default="runs/scaling")
        p.add_argument("--png")
        if mode == "run":
            p.add_argument("--repeat", type=int, default=1)
            p.add_argument("--packed", type=int, default=1,
                           help="run the 1-rank case as this many copies at once (all cores busy)")
        else:
            p.add_argument("--time", default="02:00:00")
            p.add_argument("--partition")
    p = sub.add_parser("iterations")
    p.add_argument("case")
    p.add_argument("--ranks", type=lambda s: [int(x) for x in s.split(",")], required=True)
    p.add_argument("--steps", type=int, default=3)
    p.add_argument("--on-one", action="store_true",
                   help="count each P on one process, its multigrid's levels laid out as on P ranks (needs --cuts-from)")
    p.add_argument("--cuts-from", help="a `tessera balance` JSON (the model's D/balance.json): each P runs on "
                   "its balanced cuts and grid, as the model with --cuts balanced takes them")
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--out", default="runs/scaling")
    p = sub.add_parser("report")
    p.add_argument("--out", default="runs/scaling")
    p.add_argument("--png")
    p = sub.add_parser("network")
    p.add_argument("--out", default="runs/scaling")
    p.add_argument("--measure", action="store_true", help=argparse.SUPPRESS)
    p = sub.add_parser("model")
    p.add_argument("case")
    p.add_argument("--bodies", help="DEM scenes: the checkpoint whose bodies the ranks share")
    p.add_argument("--png", help="draw the predicted speed-up and time (with the measured points) here")
    p.add_argument("--balance", help="reuse this `tessera balance` JSON (an earlier model's D/balance.json, the same "
                   "case, bodies, --set and rank counts) instead of counting again (for a coupled case, minutes)")
    p.add_argument("--cuts", choices=["equal", "balanced"], default="equal",
                   help="DEM scenes: the cut planes the runs used (domain.cuts from `tessera balance`: balanced)")
    p.add_argument("--message-cost", choices=["sizes", "line"], default="sizes",
                   help="each point-to-point message priced between network.json's measured sizes (default), or by "
                        "the latency-bandwidth line fitted over them all (the models until 2026-12-05)")
    p.add_argument("--ranks", type=lambda s: [int(x) for x in s.split(",")], required=True)
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--out", default="runs/scaling")
    a = ap.parse_args()
    {"run": run, "slurm": slurm, "report": report, "network": network, "model": model, "iterations": iterations}[a.mode](a)


if __name__ == "__main__":
    main()
