"""Table and figures of the cohesive zone's contraction (docs/studies/weakening.md) from its sweeps' outputs:

    python postprocess/weakening_cohesive_zone.py --dir out/docs/weakening -o docs/studies/img --tables docs/studies

(``bash postprocess/docs_numbers.sh weakening_cohesive_zone`` runs the sweeps and then this.)  The study's
code is ``parslip.studies.weakening.cohesive_zone``; this script only parses.
"""
import argparse
import sys

from parslip.studies.weakening import cohesive_zone


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dir", default="out/docs/weakening", help="where the study's sweeps wrote their points")
    p.add_argument("-o", "--img", default="docs/studies/img", help="where the figures go")
    p.add_argument("--tables", default="docs/studies", help=f"where {cohesive_zone.NAME}.csv goes")
    a = p.parse_args(argv)
    print(cohesive_zone.tabulate(a.dir, a.img, a.tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())
