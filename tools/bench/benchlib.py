"""Shared helpers of the benchmark runners in tools/bench (dem_bed, clump_bed)."""
import os
import re
import shutil
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHARED = os.environ.get("TESSERA_SHARED", os.path.join(os.path.dirname(ROOT), "shared"))
PEERS = os.path.join(SHARED, "bench", "peers")
TESSERA = os.environ.get("TESSERA_BIN", os.path.join(ROOT, "build", "bin", "tessera"))
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


def ensure(tools, name="bench"):
    """Installs the Debian packages of the peers a benchmark runs when their commands are missing
    (as tools/setup.sh does for the build): tools maps a command (or a file path) to its package.
    Builds Tessera first if its binary is missing."""
    missing = sorted({pkg for tool, pkg in tools.items()
                      if not (os.path.exists(tool) if tool.startswith("/") else shutil.which(tool))})
    if missing:
        print(f"{name}: installing {' '.join(missing)} (Debian packages)", flush=True)
        sudo = [] if os.geteuid() == 0 else ["sudo"]
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        subprocess.run(sudo + ["apt-get", "update", "-qq"], check=True, env=env)
        subprocess.run(sudo + ["apt-get", "install", "-y", "-qq", "--no-install-recommends"] + missing, check=True,
                       env=env, stdout=subprocess.DEVNULL)
    if not os.path.exists(TESSERA):
        subprocess.run([os.path.join(ROOT, "tools", "setup.sh"), "build"], check=True)


def median_range(values):
    """'median (min-max)' of repeated timings: the figure to quote is the median."""
    return statistics.median(values), min(values), max(values)
