"""Render one whole-lattice snapshot off screen: a thin script over parslip.plot.render.

    python postprocess/snapshot.py out/push.vtkhdf --step -1 --field sxy --png sxy.png

Fields: sxx, syy, sxy (rho c_r^2), vx, vy, speed (internal velocity unit).
The same picture comes from `parslip render RUN --field F --time T -o PNG`;
in ParaView open the .vtkhdf (5.12 and newer) or the .xdmf2 next to it (5.11 on).
"""
import argparse
import os
import sys

import parslip
from parslip.plot.render import FIELD_NAMES, render_frame
from parslip.errors import ConfigError

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("h5", help="run file (.vtkhdf)")
p.add_argument("--step", type=int, default=-1, help="snapshot index, -1 = last")
p.add_argument("--field", default="sxy", help=", ".join(FIELD_NAMES))
p.add_argument("--png", default=None, help="output PNG (default: next to the run file)")
a = p.parse_args()
try:
    run = parslip.open(a.h5)
    n = len(run.snapshot_times)
    if not -n <= a.step < n:
        raise ConfigError(f"--step {a.step}: accepted: -{n} <= step < {n}")
    k = a.step % n
    png = a.png or os.path.splitext(a.h5)[0] + f"_{a.field}_{k}.png"
    fr = render_frame(run, a.field, float(run.snapshot_times[k]), png)
except ConfigError as e:
    print(f"snapshot.py: error: {e}", file=sys.stderr)
    sys.exit(e.exit_code)
print(png, f"(step {fr.step} of {n}, t = {fr.time:.3f} l/c_r)")
