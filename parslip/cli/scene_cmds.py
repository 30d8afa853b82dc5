"""Subcommands that describe a scene without running it: info, keys.

Each subcommand adds its parser in ``register`` and does its work in a
``cmd_*`` function that returns the exit code; heavy imports stay inside it.
"""
from __future__ import annotations

import argparse

# The units every scene and output is in, as the help of ``parslip``, ``run`` and ``info`` gives them.
UNITS_HELP = """units: a = 1 (lattice spacing), node mass = 1, velocities in c_r of the top
block (or c_s with material.velocity_unit = "c_s"); scene times, like the
output's, are in l/c_r with l = top_cols * a the contact length; v0 is in c_r.
`parslip keys` lists every scene key with its default, units and range."""


def register(sub) -> None:
    i = sub.add_parser("info", help="derived quantities, cost, memory, output size, what is left out, warnings",
                       epilog=UNITS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    i.add_argument("scene")
    i.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    i.add_argument("--ranks", type=int, default=1, metavar="N",
                   help="rank count the memory and wall-time estimates are for (default 1)")
    i.add_argument("--json", action="store_true",
                   help="print one JSON object (the scaling model's figures on --ranks, the memory) and nothing else")
    i.set_defaults(func=cmd_info)
    k = sub.add_parser("keys", help="every scene key with default, units and accepted range")
    k.set_defaults(func=cmd_keys)


def cmd_info(args) -> int:
    from .info import cmd_info as info
    return info(args)


def cmd_keys(args) -> int:
    from ..scene.schema import describe_keys
    print(describe_keys())
    return 0
