"""Tables and figures of one study of docs/studies/cracks.md from its sweeps' outputs:

    python postprocess/cracks.py <energy|precursors|supershear|healing> --dir out/docs/cracks \
        -o docs/studies/img --tables docs/studies

(``bash postprocess/docs_numbers.sh cracks_<study>`` runs the sweeps and then this.)  With ``--refit`` a
study that can (precursors) fits again from the tables already in ``--tables``, without its runs:

    python postprocess/cracks.py precursors --refit -o docs/studies/img --tables docs/studies

The study's code is ``parslip.studies.cracks.<study>``; this script only parses.
"""
import argparse
import sys

from parslip.studies import cracks


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("study", help=f"one of {', '.join(cracks.STUDIES)}")
    p.add_argument("--dir", default="out/docs/cracks", help="where the study's sweeps wrote their points")
    p.add_argument("-o", "--img", default="docs/studies/img", help="where the figures go")
    p.add_argument("--tables", default="docs/studies", help="where cracks_<study>.csv goes")
    p.add_argument("--refit", action="store_true", help="fit again from the tables in --tables, without the runs "
                   "(precursors)")
    a = p.parse_args(argv)
    if a.study not in cracks.STUDIES:
        print(f"cracks.py: study {a.study!r}: accepted: {', '.join(cracks.STUDIES)}", file=sys.stderr)
        return 2
    if a.refit:
        if a.study not in cracks.REFIT:
            print(f"cracks.py: --refit with study {a.study!r}: accepted: {', '.join(cracks.REFIT)}", file=sys.stderr)
            return 2
        print(cracks.refit(a.study, a.img, a.tables))
        return 0
    print(cracks.tabulate(a.study, a.dir, a.img, a.tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())
