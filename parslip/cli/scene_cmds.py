"""Subcommands that describe a scene without running it: info, keys.

Each subcommand adds its parser in ``register`` and does its work in a
``cmd_*`` function that returns the exit code; heavy imports stay inside it.
"""
from __future__ import annotations

import argparse


def register(sub) -> None:
    from .main import UNITS_HELP
    i = sub.add_parser("info", help="derived quantities, cost, memory, output size, what is left out, warnings",
                       epilog=UNITS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    i.add_argument("scene")
    i.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    i.add_argument("--ranks", type=int, default=1, metavar="N",
                   help="rank count the memory and wall-time estimates are for (default 1)")
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
