"""The ``parslip`` command: run a scene, describe a scene, list the keys.

Responsible for turning the command line into a run and every failure into
one line and an exit code: 2 for bad input (scene, overrides, output path,
rank count, time step), 3 for a run that failed on the way (non-finite state,
slip beyond the halo).  Rank 0 decides anything on the filesystem and
broadcasts the decision; every rank then takes the same branch.

    mpirun -n 2 parslip run run/push.toml
    parslip info run/push.toml --set drive.v0=1e-2
    parslip keys
"""
from __future__ import annotations

import argparse
import importlib
import os
import sys

from ..errors import EXIT_BAD_INPUT, ConfigError
from ..parallel.launcher import start_or_refuse
from ..scene.load import load_scene_file, parse_set, resolve
from ..scene.schema import describe_keys

UNITS_HELP = """units: a = 1 (lattice spacing), node mass = 1, velocities in c_r of the top
block (or c_s with material.velocity_unit = "c_s"); scene times, like the
output's, are in l/c_r with l = top_cols * a the contact length; v0 is in c_r.
`parslip keys` lists every scene key with its default, units and range."""


# Further subcommands live in their own modules: each has ``register(sub)``,
# which adds its parser with ``set_defaults(func=...)``; ``func(args)`` returns
# the exit code.  Their heavy imports stay inside ``func``.
COMMAND_MODULES = ("parslip.cli.analysis_cmds", "parslip.cli.viz_cmds", "parslip.cli.bench_cmds",
                   "parslip.cli.paper_cmds")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="parslip", description="Onset of frictional slip at adhesive elastic "
                                "interfaces on a distributed Born lattice.", epilog=UNITS_HELP,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run a scene (under mpirun for several ranks)", epilog=UNITS_HELP,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    r.add_argument("scene", help="TOML scene file, e.g. run/push.toml")
    r.add_argument("--out", help="output HDF5 file (default: out/<scene>.vtkhdf); opens in ParaView/pyvista")
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene key; the value is a TOML literal (drive.v0=1e-2, drive.mode=pull)")
    r.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    r.add_argument("--restart", metavar="CHECKPOINT|auto",
                   help="continue from a checkpoint (OUT.ckpt.h5), appending to --out; 'auto': continue from "
                        "OUT.ckpt.h5 if it exists and the run is not complete, else start (nothing if complete); "
                        "any rank count")
    r.add_argument("--stop-after", metavar="WALLTIME",
                   help="wall-clock time (HH:MM:SS or seconds) after which the run writes a checkpoint and "
                        "stops cleanly, printing the command that continues it")
    r.add_argument("--no-png", action="store_true", help="skip the space-time PNG")
    r.add_argument("--quiet", action="store_true", help="no progress lines")
    i = sub.add_parser("info", help="derived quantities, cost, memory, output size, what is left out, warnings",
                       epilog=UNITS_HELP,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    i.add_argument("scene")
    i.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    i.add_argument("--ranks", type=int, default=1, metavar="N",
                   help="rank count the memory and wall-time estimates are for (default 1)")
    sub.add_parser("keys", help="every scene key with default, units and accepted range")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return p


def _comm():
    from mpi4py import MPI
    return MPI.COMM_WORLD


def _bcast(comm, fn):
    """Run ``fn`` on rank 0 and broadcast its value or its ConfigError."""
    res = None
    if comm.Get_rank() == 0:
        try:
            res = ("ok", fn())
        except ConfigError as e:
            res = ("err", str(e))
    res = comm.bcast(res, root=0)
    if res[0] == "err":
        raise ConfigError(res[1])
    return res[1]


def load(scene_path: str, sets: list[str]) -> dict:
    raw = load_scene_file(scene_path)
    return resolve(raw, [parse_set(s) for s in sets])


def _out_path(args, must_exist: bool = False, may_exist: bool = False) -> str:
    """The output file (default out/<scene>.vtkhdf): new unless --overwrite, existing for a restart."""
    out = args.out or os.path.join("out", os.path.splitext(os.path.basename(args.scene))[0] + ".vtkhdf")
    if os.path.isdir(out):
        raise ConfigError(f"--out {out!r}: is a directory; accepted: a file path")
    if must_exist:
        if not os.path.isfile(out):
            raise ConfigError(f"--out {out!r}: no such file; a restart appends to the output file of the run that "
                              f"wrote the checkpoint; accepted: that file")
        return out
    if os.path.exists(out) and not (args.overwrite or may_exist):
        raise ConfigError(f"--out {out!r}: exists; accepted: a new path, --overwrite to replace it, or "
                          f"--restart to continue it")
    d = os.path.dirname(out)
    try:
        if d:
            os.makedirs(d, exist_ok=True)
        if not os.access(d or ".", os.W_OK):
            raise PermissionError
    except OSError:
        raise ConfigError(f"--out {out!r}: cannot write in {d or '.'!r}; accepted: a writable path") from None
    return out


def cmd_info(args) -> int:
    from .info import cmd_info as info
    return info(args)


def cmd_run(args) -> int:
    from .run import cmd_run as run
    return run(args, _comm(), lambda fn: _bcast(_comm(), fn), load, _out_path)


ABORT_GRACE_S = 1.0     # s: time for the launcher to forward a failing rank's traceback


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.cmd == "run" and (refused := start_or_refuse()):   # before anything touches MPI
        return refused
    try:
        return _main(args)
    except Exception:
        # An unexpected error on one rank must not leave the others waiting
        # in a collective forever: print it and take the whole job down.
        if args.cmd == "run" and _comm().Get_size() > 1:
            import traceback
            comm = _comm()
            traceback.print_exc()
            # Our own line: the MPI library's "MPI_Abort" notice races the launcher's shutdown and is
            # sometimes lost, so the user would not learn why the other ranks stopped.
            print(f"parslip {comm.Get_rank()}/{comm.Get_size()} ERROR: this rank failed; MPI_Abort(1) ends "
                  f"every rank", file=sys.stderr)
            sys.stderr.flush()
            # The launcher's proxy forwards this rank's stderr asynchronously, and
            # Abort kills the proxies: without a pause the message that says what
            # went wrong is lost about one time in three (measured, both MPIs).
            import time
            time.sleep(ABORT_GRACE_S)
            _comm().Abort(1)
        raise


def _main(args) -> int:
    try:
        if args.cmd == "keys":
            print(describe_keys())
            return 0
        if args.cmd == "info":
            return cmd_info(args)
        if args.cmd == "run":
            return cmd_run(args)
        return args.func(args)
    except ConfigError as e:
        rank = 0
        if args.cmd == "run":
            rank = _comm().Get_rank()
        if rank == 0:
            print(f"parslip: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
