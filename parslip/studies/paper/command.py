"""``parslip paper``'s work, behind its argument parsing (``cli.paper_cmds``): check the roles and the
reading, make the output directory, then reproduce the paper (``study.reproduce``) or score its open
readings (``study.scan_readings``), and print what was written.

Bad input (an unknown role, a bad ``--set``, an output directory that cannot be made) raises
``ConfigError``: one line naming what and what is accepted, exit 2.  Under several ranks every rank calls
``main``; rank 0 prints.
"""
from __future__ import annotations

import os

from ...errors import ConfigError
from ...scene.load import load, overrides
from . import study

PER_NODE = "per_node"       # load.FN = per_node: F_N per node of the top row, for every run's own width


def check_roles(roles) -> list:
    """The roles asked for, each one of ``study.ORDER``."""
    for role in roles or ():
        if role not in study.ORDER:
            raise ConfigError(f"--role {role!r}: unknown; accepted: {', '.join(study.ORDER)}")
    return list(roles) if roles else None


def reading(set_items) -> dict:
    """``--set KEY=VALUE`` items as the reading every run takes (flat dotted keys), each key checked by the
    scene loader (one line naming it and what it accepts); ``load.FN = per_node`` passes as it is."""
    sets = {}
    for key, value in overrides(set_items):
        if key == "load.FN" and value == PER_NODE:
            sets[key] = value
            continue
        load({}, {key: value})
        sets[key] = value
    return sets


def make_out(out: str) -> None:
    try:
        os.makedirs(out, exist_ok=True)
    except OSError as e:
        raise ConfigError(f"--out {out!r}: cannot create ({e.strerror}); accepted: a writable directory") \
            from None


def main(out: str, roles=None, set_items=(), readings: bool = False, shrink: bool = False,
         figures: bool = True, rerun: bool = False, comm=None) -> int:
    """``parslip paper`` on every rank of ``comm`` (None: this process); returns the exit code."""
    from ...engine.progress import setup_logging
    roles = check_roles(roles)
    sets = reading(set_items)
    make_out(out)
    rank = comm.Get_rank() if comm is not None else 0
    setup_logging(rank, comm.Get_size() if comm is not None else 1)
    if readings:
        study.scan_readings(out, sets, shrink, comm, rerun=rerun)
        if rank == 0:
            with open(os.path.join(out, "readings.md")) as fh:
                print(fh.read())
        return 0
    res = study.reproduce(out, roles, sets, shrink, figures, comm, rerun)
    if rank == 0:
        from .claims import counts, share_agreeing
        c = counts(res["rows"])
        print(f"{c['agrees']} of {len(res['rows'])} claims agree ({share_agreeing(res['rows']):.0%}), "
              f"{c['disagrees']} disagree, {c['not measured']} not measured; {res['seconds']:.0f} s")
        print(os.path.join(out, "claims.md"))
        print(os.path.join(out, "claims.json"))
    return 0
