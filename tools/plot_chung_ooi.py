#!/usr/bin/python3
"""Chung & Ooi (2011) Test 4 figure: tangential restitution and spin after an oblique impact against
the incident angle, Tessera (from build/bin/test_chung_ooi) and rigid-body sliding theory.

usage: tools/plot_chung_ooi.py [--out docs/figures/chung_ooi_test4.png]
"""
import argparse
import os
import re
import subprocess
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "docs/figures/chung_ooi_test4.png"))
    a = ap.parse_args()
    out = subprocess.run([os.path.join(ROOT, "build/bin/test_chung_ooi"), "--gtest_filter=*Sliding*"],
                         capture_output=True, text=True).stdout
    rows = [tuple(float(v) for v in m.groups())
            for m in re.finditer(r"^\s+(\d+)\s+([-\d.]+)\s+([-\d.]+)\s+([-\d.]+)\s+([-\d.]+)\s+([-\d.]+)$", out, re.M)]
    if not rows:
        sys.exit("plot_chung_ooi.py: no table in the test output (build first)")
    ang, et, et_th, w, w_th, reb = zip(*rows)
    mu, e = 0.092, 0.98
    import math
    crit = math.degrees(math.atan(3.5 * mu * (1 + e)))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    a1.plot(ang, et, "o", label="Tessera (Hertz-Mindlin)")
    th = [(x, y) for x, y in zip(ang, et_th) if x > crit]
    a1.plot([x for x, _ in th], [y for _, y in th], "-", label="rigid body, sliding")
    a1.axvline(crit, color="gray", ls=":", label=f"sliding from {crit:.1f} deg")
    a1.set_xlabel("incident angle from the normal (deg)")
    a1.set_ylabel("tangential restitution e_t = v_t'/v_t")
    a1.legend()
    a2.plot(ang, w, "o", label="Tessera")
    th = [(x, y) for x, y in zip(ang, w_th) if x > crit]
    a2.plot([x for x, _ in th], [y for _, y in th], "-", label="rigid body, sliding")
    a2.axvline(crit, color="gray", ls=":")
    a2.set_xlabel("incident angle from the normal (deg)")
    a2.set_ylabel("spin after impact (rad/s)")
    a2.legend()
    fig.suptitle("Chung & Ooi (2011) Test 4: Al oxide sphere on a rigid plane, 3.9 m/s, mu = 0.092, e = 0.98")
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(a.out)


if __name__ == "__main__":
    main()
