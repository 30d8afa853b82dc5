"""Tables and figures of the studies of docs/studies/weakening.md from their sweeps' outputs:

    python postprocess/weakening.py <andrews|kammer> --dir out/docs/weakening -o docs/studies/img --tables docs/studies

(``bash postprocess/docs_numbers.sh weakening_andrews`` runs the sweeps and then both: Kammer's study reads
Andrews' runs.)  The study's code is ``parslip.studies.weakening.<study>``; this script only parses.
"""
import argparse
import sys

from parslip.studies import weakening


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("study", help=f"one of {', '.join(weakening.STUDIES)}")
    p.add_argument("--dir", default="out/docs/weakening", help="where the study's sweeps wrote their points")
    p.add_argument("-o", "--img", default="docs/studies/img", help="where the figures go")
    p.add_argument("--tables", default="docs/studies", help="where weakening_<study>.csv goes")
    a = p.parse_args(argv)
    if a.study not in weakening.STUDIES:
        print(f"weakening.py: study {a.study!r}: accepted: {', '.join(weakening.STUDIES)}", file=sys.stderr)
        return 2
    print(weakening.tabulate(a.study, a.dir, a.img, a.tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())
