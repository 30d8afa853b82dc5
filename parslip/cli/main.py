"""The ``parslip`` command: run a scene, describe a scene, list the keys.

Responsible for turning the command line into a run and every failure into
one line and an exit code: 2 for bad input (scene, overrides, output path,
rank count, time step), 3 for a run that failed on the way (non-finite state,
slip beyond the halo).  Rank 0 decides anything on the filesystem and
broadcasts the decision; every rank then takes the same branch.

    mpirun -n 2 parslip run run/push.toml
    parslip info run/push.toml --set drive.v0=1e-2
    parslip keys
    parslip --version
"""
from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import EXIT_BAD_INPUT, ConfigError
from .scene_cmds import UNITS_HELP


# Further subcommands live in their own modules: each has ``register(sub)``,
# which adds its parser with ``set_defaults(func=...)``; ``func(args)`` returns
# the exit code.  Their heavy imports stay inside ``func``.
COMMAND_MODULES = ("parslip.cli.scene_cmds", "parslip.cli.analysis_cmds", "parslip.cli.viz_cmds", "parslip.cli.bench_cmds",
                   "parslip.cli.paper_cmds", "parslip.cli.sweep_cmds", "parslip.cli.draw_cmds")


class _Version(argparse.Action):
    """``--version``: the version and the commit (``version.describe``), asked of git only when given."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        from ..version import describe
        print(describe())
        parser.exit()


def _top_parser() -> argparse.ArgumentParser:
    """The command's own options, before any subcommand's parser is built."""
    p = argparse.ArgumentParser(prog="parslip", description="Onset of frictional slip at adhesive elastic "
                                "interfaces on a distributed Born lattice.", epilog=UNITS_HELP,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action=_Version, help="print the version and the commit of this checkout (or "
                   "that it is an installed package), then exit")
    return p


def _parser() -> argparse.ArgumentParser:
    p = _top_parser()
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
    r.add_argument("--watchdog", type=float, metavar="SECONDS",
                   help="on several ranks: abort the job (exit 3, output marked failed, one line naming the rank "
                        "that stopped answering) when the ranks have not agreed for this many seconds (default: "
                        "the scene's run.watchdog, 180 s; 0 = off)")
    r.add_argument("--no-png", action="store_true", help="skip the space-time picture (OUT_spacetime.png)")
    r.add_argument("--quiet", action="store_true", help="no progress lines")
    r.set_defaults(func=lambda a: _cmd_run(a), mpi=True)
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return p


def _cmd_run(args) -> int:
    from .run import cmd_run
    return cmd_run(args, args.comm)


def main(argv=None) -> int:
    """Parse, start MPI only when a launcher started several processes, run the subcommand, and map
    every failure to one line and its exit code (the errors carry them: ``parslip.errors``)."""
    if (sys.argv[1:] if argv is None else list(argv))[:1] == ["--version"]:
        # Answered before the subcommands' parsers are built (some import the analysis, hence numpy), so an
        # installed package tells its version even where its dependencies are missing.
        _top_parser().parse_args(["--version"])
    args = _parser().parse_args(argv)
    comm = None
    if getattr(args, "mpi", False):
        from ..parallel.launcher import LauncherError, world_comm
        try:
            comm = world_comm()                 # None for one process: no MPI library is loaded
        except LauncherError as e:
            if e.speak:
                print(f"parslip: error: {e}", file=sys.stderr)
            return EXIT_BAD_INPUT
    args.comm = comm
    rank = comm.Get_rank() if comm is not None else 0
    try:
        return args.func(args)
    except ConfigError as e:
        if rank == 0:
            print(f"parslip: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
