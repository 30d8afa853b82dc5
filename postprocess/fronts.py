"""Rupture-front catalogue of a run: first break, then each front's nucleation
time and place, direction, kind, speeds, width and slip (x in l, t in l/c_r,
v in c_r, width in a).  The same as `parslip fronts RUN`.

    python postprocess/fronts.py out/push.vtkhdf [--max-gap 3.0]
"""
import argparse

import parslip
from parslip import analysis
from parslip.analysis.fronts import MAX_GAP, table

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("h5")
p.add_argument("--max-gap", type=float, default=MAX_GAP, help="longest pause of a tip whose bond re-attached, l/c_r")
a = p.parse_args()
run = parslip.open(a.h5)
t0, x0 = analysis.first_break(run.interface)
print("no bond broke" if t0 is None else f"first break at t = {t0:.3f} l/c_r, x/l = {x0[:6].round(3).tolist()}")
print(table(run.fronts(max_gap=a.max_gap)))
