"""Subcommands that read run files: fronts, figures, compare, accuracy.

Each subcommand adds its parser in ``register`` and does its work in a
function that imports what it needs, so `parslip --help` stays fast.  Bad
input (missing file, not a run file, unknown field) raises ``ConfigError``:
one line and exit code 2.
"""
from __future__ import annotations

import argparse
import os


def register(sub) -> None:
    from ..analysis.friction import MIN_DROP
    from ..analysis.fronts import MAX_GAP, MIN_SITES, WINDOW, field_help
    """Add this module's subcommands to the ``parslip`` parser."""
    raw = argparse.RawDescriptionHelpFormatter
    f = sub.add_parser("fronts", help="rupture-front catalogue and friction record (mu_s, precursors) of a run "
                                      "(table, or JSON with --json)",
                       formatter_class=raw, description=FRONTS_HELP + field_help())
    f.add_argument("run", help="run file written by `parslip run` (.vtkhdf)")
    f.add_argument("--json", action="store_true",
                   help="print one JSON object: first break, static peak, precursors and the list of fronts")
    f.add_argument("--min-sites", type=int, default=MIN_SITES,
                   help=f"drop fronts that broke fewer bonds (default {MIN_SITES})")
    f.add_argument("--max-gap", type=float, default=MAX_GAP,
                   help=f"longest pause of a tip whose bond re-attached, in l/c_r (default {MAX_GAP:g})")
    f.add_argument("--min-drop", type=float, default=MIN_DROP,
                   help=f"a slip event is a drop of mu by at least this share of its largest value "
                        f"(default {MIN_DROP:g})")
    f.add_argument("--window", type=int, default=WINDOW,
                   help=f"local speed fitted over 2*WINDOW+1 sites (default {WINDOW})")
    f.set_defaults(func=cmd_fronts)

    g = sub.add_parser("figures", help="the paper's figure set for one run, as PNG and PDF",
                       formatter_class=raw, description=FIGURES_HELP)
    g.add_argument("run", help="run file written by `parslip run` (.vtkhdf)")
    g.add_argument("-o", "--out", required=True, help="directory for the figures (created)")
    g.add_argument("--only", action="append", metavar="NAME",
                   help="write only this figure (repeatable): " + ", ".join(FIGURE_NAMES))
    g.set_defaults(func=cmd_figures)

    c = sub.add_parser("compare", help="overlay front speeds of several runs (v0 sweep, push against pull)",
                       formatter_class=raw, description=COMPARE_HELP)
    c.add_argument("runs", nargs="+", metavar="RUN", help="run files written by `parslip run`")
    c.add_argument("-o", "--out", required=True, help="directory for the figure and the table (created)")
    c.add_argument("--scale", default="auto", help="v0: v/v0 against x_tip/l; c_r: |v|/c_r against the distance "
                   "from the nucleation site; auto (default): v0 when the runs' v0 differ")
    c.add_argument("--fronts", type=int, default=3, help="how many fronts, one panel each (default 3)")
    c.set_defaults(func=cmd_compare)

    a = sub.add_parser("accuracy", help="accuracy study: error of each fidelity knob against its finest setting, "
                       "and its run time", formatter_class=raw, description=ACCURACY_HELP)
    a.add_argument("scene", help="TOML scene, e.g. run/push.toml")
    a.add_argument("-o", "--out", required=True, help="directory for the runs, accuracy.csv/.md and the Pareto plot")
    a.add_argument("--knob", action="append", metavar="NAME",
                   help="only this knob (repeatable): " + ", ".join(KNOB_NAMES))
    a.add_argument("--quick", action="store_true", help="only the first variant of each knob")
    a.add_argument("--duration", type=float, help="drive time in l/c_r (default: 32 for push/pull, 76 for shear: "
                   "just past the first three nucleations)")
    a.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene key in every run (TOML literal)")
    a.add_argument("--repeat", type=int, default=1, help="runs per setting; each time reported is the smallest "
                   "(default 1)")
    a.add_argument("--redraw", action="store_true", help="run nothing: redraw accuracy.md and the Pareto plot "
                   "from the accuracy.csv in --out")
    a.set_defaults(func=cmd_accuracy)


FRONTS_HELP = """Detect every rupture front from the bond events (/interface/events; the frames
of /interface/intact for a file written before events existed) and the interface
displacements, and give each front's fields (listed below).
Then the friction record: the first break, the slip onset (every bond broken
once), the static peak mu_s = max -F_T/F_N up to the slip onset, its time and
its place relative to the first break, and the precursors."""


FIGURE_NAMES = ("spacetime", "front_speed", "interface_stress", "stress_maps", "slip_records",
                "slip_behind_tips", "slip_velocity", "pulse_width", "mode2_fit", "friction", "stick_slip")

FIGURES_HELP = """Write the figure set of the paper's Sec. 3 and appendices for one run:
space-time diagram with the detected fronts (Figs. 2b/4b/6b), front speed v/c_r
against x_tip/l (2c/4c/6c), interface sigma_xy and sigma_yy (rho c_r^2) about the
leading tip (3b-c/5b-c/7b-c), stress maps (3a/5a/7a/8, when parslip.plot.render
is present), u(t) at three points (10), Delta u and Delta v behind the tips (9),
slip velocity (app. C), pulse width in a (app. A), Mode II fit K_II (rho c_r^2
l^1/2) and x_p (l) (app. B, also as mode2_fit.csv); beyond the paper, friction:
mu(t) = -F_T/F_N with the first break, the slip onset, the static peak mu_s and
each front's nucleation and fate marked, above the fronts' tips x_tip(t)."""

COMPARE_HELP = """Overlay the front speeds of several runs: v/v0 against x_tip/l for a v0 sweep
(Fig. 2d), |v|/c_r against distance from the nucleation site for push against
pull (appendix D).  Also writes compare_speed.csv (mean speeds in c_r and / v0)."""


KNOB_NAMES = ("time_step", "precision", "substrate_size", "substrate_model", "cadence", "preset")

ACCURACY_HELP = """Vary one fidelity knob at a time against its finest setting, each run through
`parslip run` in a subprocess (snapshots off, drive shortened), and report per
variant: wall time (s), and the error in first-break time (l/c_r) and site (l),
nucleation interval (relative), mean speed of the first three fronts (relative),
slip per front (relative) and the fraction of the intact-bond space-time map that
disagrees.  Times: the whole subprocess, its time loop, and its drive phase (wall
and CPU, from the run's log; the Pareto plot uses the drive-phase CPU time).
Knobs: time_step (time.safety 0.9, 0.5, 0.25 against 0.1), precision
(time.precision float32 against float64), substrate_size (2 l x 2 and 3 l x 2 top
rows against 5 l x 4), substrate_model (material.bottom_kn 1e3, 1e4 and
lattice.substrate = rigid against k_n = 100), cadence (output.interface_dt 1, 2,
5 a/c_r against 0.25), preset (parslip.scene.presets QUICK_LOOK against
PUBLICATION).  A knob whose key the engine refuses is reported as unavailable."""


def _positive(name: str, value, accepted: str) -> None:
    """One-line ConfigError unless an option's value is > 0."""
    from ..errors import ConfigError
    if not value > 0:
        raise ConfigError(f"--{name} {value!r}: out of range; {accepted}")


def cmd_fronts(args) -> int:
    import json

    from ..errors import ConfigError

    from ..analysis.fronts import table
    from ..analysis.results import open as open_run

    _positive("min-sites", args.min_sites, "accepted: an integer >= 1")
    _positive("max-gap", args.max_gap, "accepted: a time > 0 in l/c_r")
    _positive("window", args.window, "accepted: an integer >= 1")
    if not 0 < args.min_drop < 1:
        raise ConfigError(f"--min-drop {args.min_drop!r}: out of range; accepted: a share of mu between 0 and 1")
    run = open_run(args.run)
    kw = dict(max_gap=args.max_gap, min_sites=args.min_sites, window=args.window)
    fr = run.fronts(**kw)
    pre = run.precursors(**kw)
    has_mu = "mu" in run.interface
    slips = run.slip_events(args.min_drop, **kw) if has_mu else []
    if args.json:
        fronts = [f.to_dict() for f in fr]        # every registered per-front field (analysis.fronts.FIELDS)
        tb, xb = run.first_break
        print(json.dumps({"run": args.run, "first_break": {"time": tb, "x": [float(v) for v in xb]},
                          "static_peak": run.static_peak.to_dict() if has_mu else None,
                          "precursors": [p.to_dict() for p in pre], "fronts": fronts,
                          "slip_events": [e.to_dict() for e in slips]}))
        return 0
    print(f"{args.run}: {run.mode}, v0/c_r = {run.v0:g}, {len(run.times)} frames x {len(run.x)} sites; "
          f"{len(fr)} rupture fronts")
    if run.status != "complete":      # a run still written, stopped or failed: only its frames on disk count
        print(f"  status {run.status!r}: the file holds the {len(run.times)} frames it had written to disk")
    if fr:
        print(table(fr))
    if has_mu:
        from ..analysis.friction import summary_lines
        from ..analysis.friction import slip_event_lines
        print("\n".join(summary_lines(run, **kw)))
        print("\n".join(slip_event_lines(slips, args.min_drop)))
    return 0


def cmd_figures(args) -> int:
    from ..plot import figures
    from ..analysis.results import open as open_run
    from ..errors import ConfigError

    for name in args.only or ():
        if name not in FIGURE_NAMES:
            raise ConfigError(f"--only {name!r}: unknown figure; accepted: {', '.join(figures.FIGURES)}")
    from ..engine.progress import setup_logging
    setup_logging(0, 1)                 # the figure code logs what it skips (stress maps)
    run = open_run(args.run)
    _out_dir(args.out)
    for p in figures.write_all(run, args.out, args.only):
        print(p)
    return 0


def cmd_compare(args) -> int:
    from ..plot import figures
    from ..analysis.results import open as open_run
    from ..errors import ConfigError

    if args.scale not in ("auto", "v0", "c_r"):
        raise ConfigError(f"--scale {args.scale!r}: unknown; accepted: auto, v0, c_r")
    _positive("fronts", args.fronts, "accepted: an integer >= 1")
    runs = [open_run(p) for p in args.runs]
    _out_dir(args.out)
    paths, rows = figures.compare_speeds(runs, args.out, n=args.fronts, scale=args.scale)
    csv = os.path.join(args.out, "compare_speed.csv")
    with open(csv, "w") as fh:
        fh.write("run,mode,v0_cr,front,mean_speed_cr,mean_speed_over_v0\n")
        for r in rows:
            fh.write(f"{r['run']},{r['mode']},{r['v0']:g},{r['front']},{r['mean_speed']:.6g},"
                     f"{r['mean_speed_over_v0']:.6g}\n")
    print(f"{'run':40s} {'mode':6s} {'v0/c_r':>8s} {'front':>5s} {'v/c_r':>10s} {'v/v0':>10s}")
    for r in rows:
        print(f"{os.path.basename(r['run']):40s} {r['mode']:6s} {r['v0']:8.3g} {r['front']:5d} "
              f"{r['mean_speed']:10.4g} {r['mean_speed_over_v0']:10.4g}")
    for p in paths + [csv]:
        print(p)
    return 0


def _out_dir(path: str) -> None:
    """Create an output directory, or one ConfigError line saying why not."""
    from ..errors import ConfigError
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as e:
        raise ConfigError(f"--out {path!r}: cannot create ({e.strerror}); accepted: a writable directory") from None


def cmd_accuracy(args) -> int:
    from ..studies import accuracy
    from ..errors import ConfigError
    from ..scene.load import load
    from ..engine.progress import setup_logging

    for name in args.knob or ():
        if name not in KNOB_NAMES:
            raise ConfigError(f"--knob {name!r}: unknown knob; accepted: {', '.join(KNOB_NAMES)}")
    if args.duration is not None:
        _positive("duration", args.duration, "accepted: a time > 0 in l/c_r")
    load(args.scene, args.set)          # bad scene: one line, exit 2
    _out_dir(args.out)
    setup_logging(0, 1)
    if args.redraw:
        csv = os.path.join(args.out, "accuracy.csv")
        if not os.path.exists(csv):
            raise ConfigError(f"--redraw: no {csv}; accepted: the --out of an earlier study")
        with open(csv) as fh:
            rows = accuracy.from_csv(fh.read())
        for p in accuracy.write_reports(rows, args.out, title=os.path.basename(args.scene)):
            print(p)
        return 0
    _positive("repeat", args.repeat, "accepted: an integer >= 1")
    rows = accuracy.study(args.scene, args.out, args.knob, args.quick, args.duration, args.set, args.repeat)
    paths = accuracy.write_reports(rows, args.out, title=os.path.basename(args.scene))
    print(accuracy.to_markdown(rows))
    for p in paths:
        print(p)
    return 0
