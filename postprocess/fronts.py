"""Rupture-front catalogue of a run: first break, then each front's nucleation
time and place, direction and speed (x in l, t in l/c_r, v in c_r).

    python postprocess/fronts.py out/push.vtkhdf [--max-gap 3.0]
"""
import argparse

from parslip import analysis

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("h5")
p.add_argument("--max-gap", type=float, default=3.0, help="largest time between linked breaks, l/c_r")
a = p.parse_args()
iface = analysis.load_interface(a.h5)
print(analysis.summary(iface))
