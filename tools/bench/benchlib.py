"""Shared helpers of the benchmark runners in tools/bench (dem_bed, clump_bed)."""
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHARED = os.environ.get("TESSERA_SHARED", os.path.join(os.path.dirname(ROOT), "shared"))
PEERS = os.path.join(SHARED, "bench", "peers")
TESSERA = os.path.join(ROOT, "build", "bin", "tessera")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OMP_NUM_THREADS="1")
ENV.pop("CI", None)


def sh(cmd, work, log, name="bench"):
    """Runs cmd in work, output to work/log; exits with a message on failure; returns the output."""
    path = os.path.join(work, log)
    with open(path, "w") as f:
        r = subprocess.run(cmd, cwd=work, env=ENV, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        sys.exit(f"{name}: {' '.join(cmd)} failed, see {path}")
    with open(path) as f:
        return f.read()


def mpirun(n):
    return ["mpirun", "--bind-to", "core", "-np", str(n)] if n > 1 else ["mpirun", "-np", "1"]


def loop_time(log, name="bench"):
    """LAMMPS/LIGGGHTS 'Loop time' line: seconds, procs, steps, atoms."""
    m = re.findall(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", log)
    if not m:
        sys.exit(f"{name}: no 'Loop time' line in a peer log")
    t, procs, steps, atoms = m[-1]
    return float(t), int(procs), int(steps), int(atoms)
