"""Subcommands that render run files or describe them to viewers: ``render``, ``xdmf``.

Each subcommand adds its parser in ``register`` and does its work in a
function that imports what it needs, so `parslip --help` stays fast.

    parslip render out/push.vtkhdf --field sxy --time 50 -o sxy.png
    parslip render out/push.vtkhdf --field sxy --movie sxy.mp4
    parslip xdmf out/push.vtkhdf          # rewrite out/push.xdmf2 (ParaView 5.11+)
"""
from __future__ import annotations

import os

FIELDS_HELP = "sxx, syy, sxy (node stress, rho c_r^2); vx, vy, speed (node velocity, internal unit: c_s by default)"


def register(sub) -> None:
    """Add this module's subcommands to the ``parslip`` parser."""
    r = sub.add_parser("render", help="render a snapshot (PNG) or all of them (MP4/GIF) off screen",
                       description="Off-screen picture of a run's snapshots: bonds coloured by a node field, "
                       "intact interface bonds in red, framed on the contact; signed fields on a scale "
                       "centred on zero.")
    r.add_argument("run", metavar="RUN", help="run file written by `parslip run` (.vtkhdf)")
    r.add_argument("--field", default="sxy", help=f"field to colour by (default sxy): {FIELDS_HELP}")
    r.add_argument("--time", type=float, default=None, metavar="T",
                   help="time in l/c_r from the start of the drive; the nearest snapshot is drawn "
                        "(default: the last snapshot)")
    out = r.add_mutually_exclusive_group()
    out.add_argument("-o", "--out", metavar="PNG",
                     help="PNG to write (default: RUN's name + _<field>_t<T>.png next to it)")
    out.add_argument("--movie", metavar="PATH", help="render every snapshot into this .mp4 or .gif instead")
    r.add_argument("--fps", type=float, default=4.0, help="movie frames (snapshots) per second (default 4)")
    r.add_argument("--clim", type=float, default=None, metavar="V",
                   help="colour limit in the field's unit: the scale is -V..V (0..V for speed); "
                        "default: the 99th percentile of |value| (over all snapshots for a movie)")
    r.set_defaults(func=cmd_render)

    x = sub.add_parser("xdmf", help="(re)write a run's XDMF sidecar, which ParaView 5.11 and newer open "
                       "as a time series", description="Write RUN's .xdmf2 sidecar: the snapshots as a "
                       "temporal collection pointing into RUN's datasets (no data copied).  `parslip run` "
                       "writes it; rerun this after renaming RUN.")
    x.add_argument("run", metavar="RUN", help="run file written by `parslip run` (.vtkhdf)")
    x.add_argument("-o", "--out", metavar="XDMF", help="sidecar to write (default: RUN with suffix .xdmf2)")
    x.set_defaults(func=cmd_xdmf)


def cmd_render(args) -> int:
    import parslip

    from ..plot.render import field_spec, render_frame, render_movie, snapshot_index

    run = parslip.open(args.run)
    field_spec(run, args.field)                 # bad field: one line before any work
    clim = None
    if args.clim is not None:
        from ..errors import ConfigError
        if not args.clim > 0:
            raise ConfigError(f"--clim {args.clim:g}: accepted: > 0, in the field's unit")
        clim = (0.0, args.clim) if args.field == "speed" else (-args.clim, args.clim)
    if args.movie:
        n = render_movie(run, args.field, args.movie, fps=args.fps, clim=clim)
        print(f"{args.movie}: {n} frames ({args.field}, t = {run.snapshot_times[0]:.3f} .. "
              f"{run.snapshot_times[-1]:.3f} l/c_r)")
        return 0
    k = snapshot_index(run, args.time)
    png = args.out or f"{os.path.splitext(args.run)[0]}_{args.field}_t{run.snapshot_times[k]:.3f}.png"
    fr = render_frame(run, args.field, args.time, png, clim=clim)
    print(f"{png}: snapshot {fr.step} of {len(run.snapshot_times)}, t = {fr.time:.3f} l/c_r, "
          f"{args.field} scale {fr.clim[0]:.3g} .. {fr.clim[1]:.3g}")
    return 0


def cmd_xdmf(args) -> int:
    from ..io.xdmf import write_xdmf

    print(write_xdmf(args.run, args.out))
    return 0
