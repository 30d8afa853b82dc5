"""``parslip paper``: the paper reproduced, claim by claim, and its open readings scored.

Argument parsing and dispatch only: the work is ``parslip.studies.paper``'s
(``command.main`` checks the input, ``study`` makes the runs and writes the
tables, ``claims`` and ``measures`` compare them with the paper).
"""
from __future__ import annotations

import argparse

PAPER_HELP = """Run (or reuse, from OUT/runs/) every scene the paper's claims need, then write
OUT/claims.md and OUT/claims.json (each claim: the paper's value, parslip's,
units, the tolerance fixed with the claim, the verdict; 'not measured' counts
against the share that agrees) and the figure set under OUT/figures/.  Roles:
push, pull (100 l/c_r), shear (300 l/c_r, three fronts), shear_maps (dense
snapshots round the first break), push_v0_1e-2 and push_v0_1e-4 (the v0 sweep),
push_l300, pull_l300, shear_l300, shear_l500 (Sec. 4.4).  About 5 minutes on
one rank when nothing is there yet (the l = 500 run 3 of them).

--readings instead scores the paper's open readings (each scene key of
parslip.studies.paper.study.READINGS flipped alone, the promising combinations, and
numerics that could cause a disagreement) by the claims the push, pull, shear
and push_v0_1e-2 runs measure: OUT/readings.md and OUT/readings.json, the runs
under OUT/readings/.  Under mpiexec -n N every run uses the N ranks (in-process,
parslip.run on the world communicator); rank 0 decides and writes the tables."""


def register(sub) -> None:
    p = sub.add_parser("paper", help="reproduce the paper: every claim checked, figures; --readings scores "
                       "the open readings", formatter_class=argparse.RawDescriptionHelpFormatter,
                       description=PAPER_HELP)
    p.add_argument("-o", "--out", required=True, help="output directory (runs, figures, claims.md/.json)")
    p.add_argument("--readings", action="store_true", help="score the open readings instead (readings.md/.json)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="a scene key for every run (a reading), TOML literal; load.FN=per_node for F_N per node")
    p.add_argument("--role", action="append", metavar="ROLE", help="only these runs (repeatable)")
    p.add_argument("--no-figures", action="store_true", help="the tables only")
    p.add_argument("--rerun", action="store_true", help="run every scene again even if OUT holds it")
    p.add_argument("--shrink", action="store_true", help="tiny lattices and short drives (a few seconds per run): "
                   "tests the pipeline, not the paper")
    p.set_defaults(func=cmd_paper, mpi=True)          # under mpiexec -n N, every run uses the N ranks


def cmd_paper(args) -> int:
    from ..studies.paper.command import main
    return main(args.out, roles=args.role, set_items=args.set, readings=args.readings, shrink=args.shrink,
                figures=not args.no_figures, rerun=args.rerun, comm=args.comm)
