"""The paper's figure set and its comparison table, from the runs in a directory.

    python postprocess/paper.py --runs out/paper -o out/paper/figures          # use existing runs
    python postprocess/paper.py --runs out/paper -o out/paper/figures --run -n 2  # make the missing ones
    python postprocess/paper.py --runs out/paper -o out/paper/figures --run --variations   # and the tests

Runs are RUNS/<role>.vtkhdf with roles push, pull, shear, push_v0_1e-2 and
push_v0_1e-4 (scenes run/<role>.toml).  Writes OUT/<role>/ (each run's
figures), OUT/v0_sweep.*, OUT/push_vs_pull.* and OUT/comparison.md; with
--variations also the runs that test each disagreement's likely reason
(RUNS/variations/<role>__<name>.vtkhdf) and OUT/variations.md.
"""
import argparse

from parslip.analysis import paper
from parslip.cli.progress import setup_logging

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--runs", required=True, help="directory of the runs, <role>.vtkhdf")
p.add_argument("-o", "--out", required=True, help="directory for the figures and comparison.md")
p.add_argument("--run", action="store_true", help="run the scenes whose output is missing (parslip run)")
p.add_argument("-n", "--ranks", type=int, default=1, help="MPI ranks for those runs (mpiexec)")
p.add_argument("--role", action="append", choices=list(paper.SCENES), help="only these roles (repeatable)")
p.add_argument("--variations", action="store_true",
               help="also the runs that test the disagreements' likely reasons, and variations.md")
a = p.parse_args()
setup_logging(0, 1)
runs = paper.reproduce(a.runs, a.out, run_missing=a.run, ranks=a.ranks, roles=a.role, variations=a.variations)
print(open(f"{a.out}/comparison.md").read())
if a.variations:
    print(open(f"{a.out}/variations.md").read())
