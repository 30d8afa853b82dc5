"""`parslip run`: the command line around ``parslip.run``.

Parses nothing itself (``cli.main`` does), starts MPI only when a launcher
started several processes, sets up logging, calls the API and maps how the
run ended to an exit code and one line:

  0    complete, or stopped with a checkpoint (SIGTERM, SIGUSR1, --stop-after): the line says how to
       continue; a SIGTERM or SIGUSR1 that comes after the run is complete, while rank 0 prints the
       catalogue or draws the picture, skips what is left of that with a line and still exits 0
  130  interrupted by Ctrl-C, with a checkpoint
  2    bad input (ConfigError)
  3    a run that failed on the way (RunError), or the job aborted by the watchdog or by a signal that
       came while a rank was blocked

On a complete run rank 0 then prints the rupture-front catalogue and draws
the space-time picture (``plot.figures.spacetime_picture``) next to the
output, before the command returns.
"""
from __future__ import annotations

import os
import sys
import time

from ..errors import EXIT_RUN_FAILED, RunError, WriteError

EXIT_INTERRUPTED = 130


def parse_walltime(text: str) -> float:
    """'HH:MM:SS', 'MM:SS' or seconds -> seconds."""
    from ..errors import ConfigError
    try:
        parts = [float(p) for p in str(text).split(":")]
        if not 1 <= len(parts) <= 3 or any(p < 0 for p in parts):
            raise ValueError
    except ValueError:
        raise ConfigError(f"--stop-after {text!r}: accepted: a wall-clock time as HH:MM:SS, MM:SS or seconds "
                          f"(e.g. 23:30:00)") from None
    s = 0.0
    for p in parts:
        s = 60 * s + p
    return s


def cmd_run(args, comm) -> int:
    """`parslip run SCENE` on every rank of ``comm`` (None: one process, no MPI)."""
    import parslip
    from ..engine.progress import setup_logging
    from ..engine.runner import continue_command
    from ..io.run_files import default_out

    rank, size = (comm.Get_rank(), comm.Get_size()) if comm is not None else (0, 1)
    log = setup_logging(rank, size)
    stop_after = parse_walltime(args.stop_after) if args.stop_after is not None else None
    out = args.out or default_out(args.scene)
    try:
        result = parslip.run(args.scene, out=out, sets=args.set, restart=args.restart, overwrite=args.overwrite,
                             comm=comm, progress=not args.quiet, stop_after=stop_after, watchdog=args.watchdog)
    except RunError as e:
        if rank == 0:
            print(f"parslip: run failed: {e}", file=sys.stderr)
        if isinstance(e, WriteError):
            _exit_now(comm, EXIT_RUN_FAILED)
        return EXIT_RUN_FAILED
    oc = result.outcome
    if not oc.complete:
        if rank == 0:
            print(f"parslip: {oc.status}; output kept in {oc.out}; continue with:\n"
                  f"  {continue_command(args.scene, args.set, oc.out, oc.checkpoint, size)}", file=sys.stderr)
        return EXIT_INTERRUPTED if oc.interrupted else 0
    _after_the_run_signals_skip(rank)
    if rank == 0 and oc.step:
        try:
            _report(result, args, log)
        except _Skipped as e:
            print(f"parslip: {e} came after the run was complete: the catalogue or the picture was skipped; "
                  f"the run is complete in {oc.out}", file=sys.stderr)
    return 0


class _Skipped(Exception):
    """A batch system's signal that came while rank 0 reports a run that is already complete."""


def _after_the_run_signals_skip(rank: int):
    """A complete run is done: the batch system's SIGTERM (or SIGUSR1, the early warning) that comes while
    the report is made ends that report, not the job with the signal's exit code.  Rank 0 leaves the report;
    the other ranks have nothing left to do and ignore it."""
    import signal

    def skip(signum, frame):
        raise _Skipped(signal.Signals(signum).name)
    for sig in (signal.SIGTERM, signal.SIGUSR1):
        signal.signal(sig, skip if rank == 0 else signal.SIG_IGN)


def _exit_now(comm, code: int):
    """After a failed write HDF5 still holds a file it could not close, and its own clean-up at exit
    crashes on it (a segfault seen with HDF5 1.14 on a full disk): end the process without that clean-up,
    after every rank has said its line and MPI is finalised."""
    sys.stdout.flush()
    sys.stderr.flush()
    if comm is not None:
        from mpi4py import MPI
        comm.Barrier()
        MPI.Finalize()
    os._exit(code)


def _report(result, args, log):
    """Rank 0, after a complete run: the front catalogue, and the space-time picture with its cost."""
    from .. import analysis, hooks, plot
    print(analysis.summary(result))
    if args.no_png:
        log.info(f"wrote {result.path}")
        return
    png = os.path.splitext(result.path)[0] + "_spacetime.png"
    t0 = time.monotonic()
    title = f"{os.path.basename(args.scene)}: {result.scene.get('drive.mode')}, " \
            f"v0/c_r = {result.scene.get('drive.v0'):g}"
    if hooks.get("hold_before_picture"):        # the test hook: wait here, as a slow picture would
        hooks.hold(f"{png}.held")
    try:
        plot.spacetime_png(result.interface, png, title)
    except OSError as e:
        log.warning(f"the space-time picture {png} was not written ({e})")
        return
    log.info(f"wrote {result.path} and {png} ({time.monotonic() - t0:.2f} s for the picture)")
