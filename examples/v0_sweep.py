"""The v0 sweep of the paper's Fig. 2d: three push scenes, and the front speeds over v0 they make.

    python examples/v0_sweep.py           # run/push_v0_1e-2.toml, run/push.toml, run/push_v0_1e-4.toml
    python examples/v0_sweep.py --quick   # the same sweep, small and short (seconds)

Runs go to out/examples/ (reused when complete); the figure, v/v0 of the first three fronts against
x_tip/l, is examples/figures/v0_sweep.png.  The paper: the curves of the three speeds coincide (v is
proportional to v0).
"""
import argparse
import os
import shutil
import sys
import tempfile

import parslip
from parslip.plot import figures

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))       # the repository, where run/ is
SCENES = ("run/push_v0_1e-2.toml", "run/push.toml", "run/push_v0_1e-4.toml")
QUICK = {"lattice.top_rows": 4, "lattice.top_cols": 24, "lattice.bottom_rows": 4, "lattice.bottom_cols": 40,
         "output.snapshots": 0}
# The quick sweep: a small lattice, v0 a factor 2 apart, each driven over the same slip (0.12 l).
QUICK_V0 = {"run/push_v0_1e-2.toml": 0.04, "run/push.toml": 0.02, "run/push_v0_1e-4.toml": 0.01}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.join("out", "examples"), help="folder of the run files")
    p.add_argument("--figures", default=os.path.join(os.path.dirname(__file__), "figures"))
    p.add_argument("--quick", action="store_true", help="small and short: seconds")
    a = p.parse_args(argv)
    runs = []
    for scene in SCENES:
        name = os.path.splitext(os.path.basename(scene))[0] + ("_quick" if a.quick else "")
        sets = None
        if a.quick:
            v0 = QUICK_V0[scene]
            sets = {**QUICK, "drive.v0": v0, "drive.duration": 0.12 / v0}
        runs.append(parslip.run(os.path.join(ROOT, scene), out=os.path.join(a.out, name + ".vtkhdf"), sets=sets,
                                restart="auto"))
    with tempfile.TemporaryDirectory() as tmp:
        paths, rows = figures.compare_speeds(runs, tmp, n=3, scale="v0")
        os.makedirs(a.figures, exist_ok=True)
        png = os.path.join(a.figures, "v0_sweep" + ("_quick" if a.quick else "") + ".png")
        shutil.copy(next(q for q in paths if q.endswith(".png")), png)
    for r in rows:
        print(f"{os.path.basename(r['run'])}: front {r['front']}, mean speed {r['mean_speed']:.3g} c_r = "
              f"{r['mean_speed_over_v0']:.3g} v0")
    print(png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
