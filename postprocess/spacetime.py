"""Space-time PNG of the interface bonds of a run (intact yellow, broken white).

    python postprocess/spacetime.py out/push.vtkhdf [--png out/push_spacetime.png]
"""
import argparse
import os

import parslip
from parslip import plot

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("h5")
p.add_argument("--png")
a = p.parse_args()
png = a.png or os.path.splitext(a.h5)[0] + "_spacetime.png"
plot.spacetime_png(parslip.open(a.h5).interface, png, os.path.basename(a.h5))
print(png)
