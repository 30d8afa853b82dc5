"""The paper reproduced: a thin wrapper of ``parslip paper`` (see ``parslip paper --help``).

    python postprocess/paper.py -o out/paper              # every run, claims.md/.json, figures
    python postprocess/paper.py -o out/paper --readings   # the open readings, scored
"""
import sys

from parslip.cli.main import main

sys.exit(main(["paper", *sys.argv[1:]]))
