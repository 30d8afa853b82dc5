"""Subcommands over many runs: `parslip sweep` (``studies.sweep``) and `parslip map` (``plot.maps``).

Bad input (a sweep file, a table, a column) is a ``ConfigError``: one line
naming the key, the value and what is accepted, exit 2; a missing optional
extra says which to install, exit 2.
"""
from __future__ import annotations

import argparse
import os
import sys

SWEEP_HELP = """Run every point of a sweep file (paths relative to the working directory):

    base = "run/push.toml"        # the scene every point starts from
    ranks_per_point = 1           # ranks per point (default 1): the job's ranks split into groups
    [set]                         # fixed overrides
    "drive.duration" = 8
    [grid]                        # cartesian product (first key slowest)
    "drive.mode" = ["push", "pull"]
    "load.FN" = [0.5, 1.0]
    [zip]                         # equal-length lists taken together, times the grid
    "interface.kx" = [0.05, 0.1]
    "interface.ky" = [0.15, 0.3]

Under mpiexec/srun the ranks split into groups of ranks_per_point, each group
running its points one after the other (one point per rank by default).
Each point writes OUTDIR/points/pNNN.vtkhdf and a record pNNN.json; at the end
OUTDIR/summary.csv and OUTDIR/summary.nc (netCDF4: xarray.open_dataset) hold one
row per point: the swept keys, status ("ok" or "failed: REASON"), first break
time (l/c_r) and place (x/l), mu_s and its place, fronts by kind and fate,
precursor arrest lengths (l), mean speeds (c_r), slip per event (l), wall time
(s), the resolved scene (JSON) and the commit.  Run it again to resume: finished
points are skipped, interrupted ones continue from their checkpoints, a point
a killed job left running is marked failed if its file says so (the watchdog).
As a Slurm job array: slurm/sweep.sbatch (one --shard per array task)."""

MAP_HELP = """Draw an observable of a sweep's summary table over two of its keys, the
marker's shape the rupture kind (o pulse, s crack, D mixed, ^ none: the contact
never slipped everywhere; x failed);
a numeric observable gets a colour scale and its value beside each marker.
Numbers spanning a factor of 8 or more get a log axis; keys with words for values
(drive.mode) are axes of categories."""


def register(sub) -> None:
    raw = argparse.RawDescriptionHelpFormatter
    s = sub.add_parser("sweep", help="run a grid or list of scenes as one job (resumable), with a summary table",
                       formatter_class=raw, description=SWEEP_HELP)
    s.add_argument("sweep", help="sweep file (TOML: base, ranks_per_point, [set], [grid], [zip])")
    s.add_argument("-o", "--out", required=True, metavar="OUTDIR",
                   help="directory for the points' files and the summary (made; the same to resume)")
    s.add_argument("--shard", default="0/1", metavar="I/N",
                   help="run only the points dealt to shard I of N (0 <= I < N; a Slurm array task each)")
    s.add_argument("--stop-after", metavar="WALLTIME",
                   help="wall-clock time (HH:MM:SS or seconds) after which no point starts and running ones stop "
                        "with a checkpoint; run the sweep again to continue")
    s.add_argument("--retry-failed", action="store_true", help="run the points recorded failed again")
    s.add_argument("--reanalyse", action="store_true",
                   help="compute the finished points' observables again from their files (after a change to "
                        "parslip.analysis), then write the summary")
    s.add_argument("--dry-run", action="store_true",
                   help="check the sweep file and print its points and what is left to run; run nothing")
    s.add_argument("--quiet", action="store_true", help="no line per point")
    s.set_defaults(func=cmd_sweep, mpi=True)

    m = sub.add_parser("map", help="an observable of a sweep's summary over two keys, rupture kind as marker (PNG)",
                       formatter_class=raw, description=MAP_HELP)
    m.add_argument("table", help="summary.csv or summary.nc of `parslip sweep`")
    m.add_argument("--x", required=True, metavar="KEY", help="column on the x axis (a swept key, e.g. load.FN)")
    m.add_argument("--y", required=True, metavar="KEY", help="column on the y axis (e.g. drive.mode)")
    m.add_argument("--color", required=True, metavar="OBSERVABLE",
                   help="column giving the colour (e.g. mu_s, rupture_kind, front_speed, n_precursors)")
    m.add_argument("-o", "--out", metavar="PNG",
                   help="the picture (default: map_<color>_<x>_<y>.png beside the table)")
    m.add_argument("--where", action="append", default=[], metavar="KEY=VALUE",
                   help="keep only the rows with this value (repeatable)")
    m.add_argument("--xscale", default="auto", choices=["auto", "linear", "log"])
    m.add_argument("--yscale", default="auto", choices=["auto", "linear", "log"])
    m.add_argument("--title", default="", help="the picture's title")
    m.set_defaults(func=cmd_map)


def _shard(text: str) -> tuple[int, int]:
    from ..errors import ConfigError
    try:
        i, n = (int(v) for v in text.split("/"))
        if n < 1 or not 0 <= i < n:
            raise ValueError
    except ValueError:
        raise ConfigError(f"--shard {text!r}: accepted: I/N with 0 <= I < N (e.g. 2/8)") from None
    return i, n


def cmd_sweep(args) -> int:
    from ..engine.progress import setup_logging
    from ..studies.sweep import run_sweep
    from .run import EXIT_INTERRUPTED, parse_walltime
    import logging

    comm = args.comm
    if args.dry_run:
        return _dry_run(args)
    rank = comm.Get_rank() if comm is not None else 0
    size = comm.Get_size() if comm is not None else 1
    setup_logging(rank, size, level=logging.WARNING)      # the points' own warnings; their progress is ours
    stop_after = parse_walltime(args.stop_after) if args.stop_after is not None else None
    echo = (lambda line: None) if args.quiet else (lambda line: print(f"parslip {rank}/{size}: {line}",
                                                                       file=sys.stderr, flush=True))
    res = run_sweep(args.sweep, args.out, comm, shard=_shard(args.shard), stop_after=stop_after,
                    echo=echo, retry_failed=args.retry_failed, reanalyse=args.reanalyse)
    if rank == 0:
        pending = sum(r["status"] == "pending" for r in res.rows)
        failed = sum(r["status"].startswith("failed") for r in res.rows)
        print(f"{len(res.rows)} points: {len(res.rows) - pending - failed} ok, {failed} failed, {pending} pending "
              f"(this job ran {res.ran}: {res.ok} ok, {res.failed} failed, {res.stopped} stopped)")
        for p in res.summary:
            print(p)
        if res.stopped:
            print("parslip: sweep stopped with checkpoints; continue with the same command", file=sys.stderr)
    return EXIT_INTERRUPTED if res.interrupted else 0


def _dry_run(args) -> int:
    """The points, their status on disk and the shard's share, without running or writing anything."""
    from ..studies import sweep as S
    from ..analysis.table import require_netcdf
    require_netcdf()
    sw = S.load_sweep(args.sweep)
    si, sn = _shard(args.shard)
    mine = {sw.points[i].name for i in S.deal([S.cost(sw, p) for p in sw.points], sn)[si]}
    print(f"{args.sweep}: base {sw.base}, {len(sw.points)} points over {', '.join(sw.swept) or '(nothing)'}, "
          f"ranks_per_point {sw.ranks_per_point}" + (f"; shard {si}/{sn} holds {len(mine)} (*)" if sn > 1 else ""))
    for p in sw.points:
        rec = S.read_record(args.out, p) if os.path.isdir(args.out) else None
        status = (rec or {}).get("status", "pending")
        here = "*" if sn > 1 and p.name in mine else " "
        print(f"  {p.name}{here} {status[:40]:40s} {p.label()}")
    return 0


def cmd_map(args) -> int:
    from ..analysis import table
    from ..errors import ConfigError
    from ..plot import maps
    from ..scene.load import overrides

    tab = table.read(args.table)
    for w in args.where:
        if "=" not in w:
            raise ConfigError(f"--where {w!r}: accepted: KEY=VALUE, e.g. drive.mode=push")
    where = dict(overrides(args.where))
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(args.table)),
                                   f"map_{args.color}_{args.x}_{args.y}.png".replace("/", "_"))
    d = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(d):
        raise ConfigError(f"-o {out!r}: no directory {d!r}; accepted: a PNG path in an existing directory")
    print(maps.draw_map(tab, args.x, args.y, args.color, out, where=where, title=args.title,
                        xscale=args.xscale, yscale=args.yscale))
    return 0
