"""The accuracy study: how much each fidelity knob changes the observables, and what it costs.

Responsible for (1) ``metrics``, the errors of one run against a reference
run: first-break time and site, nucleation interval, mean speed of the first
three fronts, slip per front, and the fraction of the space-time map of
intact bonds that disagrees on a common grid; (2) KNOBS, the data-driven list
of fidelity knobs, each a reference (its finest setting) and variants, every
setting a set of scene overrides computed from the base scene, and optionally
a limit the variants converge to (the rigid substrate); (3) ``study``,
which runs every needed setting through ``parslip run`` subprocesses, times
each one (the subprocess's wall clock; its time loop and drive phase, wall
and CPU, from its log), and reports a knob whose key the scene refuses
("unknown key", exit 2) as unavailable instead of failing; (4) the CSV and
Markdown tables (and reading the CSV back) and the Pareto plot of error
against the drive phase's CPU time.

Units: times in l/c_r, sites in l, speeds in c_r, slip in l; relative
errors are |test - ref| / |ref|; run times in seconds.
"""
from __future__ import annotations

import logging
import math
import os
import re
import subprocess
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..analysis.fronts import first_break

log = logging.getLogger("parslip")

N_FRONTS = 3            # the speed and slip errors average over the first three fronts


# --- metrics ------------------------------------------------------------------------

def _rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b) if b else (0.0 if a == b else math.inf)


def spacetime_disagreement(test, ref) -> float:
    """Fraction of the reference's (frame, site) grid where the test run's bond state differs.

    The test record is resampled onto the reference's frame times (nearest
    frame) and sites (nearest x), over the times both runs cover.
    """
    tr, tt = ref.times, test.times
    keep = tr <= min(tr[-1], tt[-1]) + 1e-12
    k = np.clip(np.searchsorted(tt, tr[keep]), 1, len(tt) - 1)
    k -= (tr[keep] - tt[k - 1]) < (tt[k] - tr[keep])            # the nearer of the two neighbours
    s = np.abs(test.x[None, :] - ref.x[:, None]).argmin(axis=1)
    a = ref.interface["intact"][keep] == 1
    b = test.interface["intact"][k][:, s] == 1
    return float(np.mean(a != b)) if a.size else math.nan


def metrics(test, ref) -> dict:
    """Errors of run ``test`` against run ``ref`` (both ``parslip.open`` results).

    first_break_t   |t_test - t_ref| of the first broken bond, l/c_r
    first_break_x   |x_test - x_ref| of its site (mean over a frame's sites), l
    interval        relative error of the mean time between nucleations at the driven edge
    speed           mean over the first three fronts of the relative error of their mean speed
    slip            mean over the first three fronts of the relative error of their slip_u
    spacetime       fraction of the intact-bond map that disagrees (``spacetime_disagreement``)
    Missing quantities (no break, too few fronts) are NaN.
    """
    from .paper.measures import interval
    tb_t, xb_t = first_break(test.interface)
    tb_r, xb_r = first_break(ref.interface)
    out = {"first_break_t": math.nan, "first_break_x": math.nan}
    if tb_t is not None and tb_r is not None:
        out["first_break_t"] = abs(tb_t - tb_r)
        out["first_break_x"] = abs(float(np.mean(xb_t)) - float(np.mean(xb_r)))
    out["interval"] = _rel(interval(test), interval(ref)) if math.isfinite(interval(ref)) else math.nan
    ft, fr = test.fronts()[:N_FRONTS], ref.fronts()[:N_FRONTS]
    n = min(len(ft), len(fr))
    out["speed"] = float(np.mean([_rel(ft[i].mean_speed, fr[i].mean_speed) for i in range(n)])) if n else math.nan
    out["slip"] = float(np.mean([_rel(ft[i].slip_u, fr[i].slip_u) for i in range(n)])) if n else math.nan
    out["spacetime"] = spacetime_disagreement(test, ref)
    return out


METRICS = ("first_break_t", "first_break_x", "interval", "speed", "slip", "spacetime")


# --- knobs --------------------------------------------------------------------------

@dataclass(frozen=True)
class Setting:
    label: str
    sets: Callable[[dict], dict]        # base scene -> overrides


@dataclass(frozen=True)
class Knob:
    name: str
    what: str
    reference: Setting                  # the finest setting
    variants: tuple[Setting, ...]
    limit: str = ""                     # label of a variant the others converge to: each is also measured against it


def _s(label: str, **sets) -> Setting:
    """A fixed setting; keyword names spell the scene key with __ for the dot (time__safety)."""
    return Setting(label, lambda scene, ov=sets: {k.replace("__", "."): v for k, v in ov.items()})


def _size(label: str, cols: int, rows: int) -> Setting:
    """Substrate of cols x top_cols nodes and rows x top_rows rows (the paper's 300 x 20 is 3 x 2)."""
    return Setting(label, lambda s: {"lattice.bottom_cols": cols * s["lattice.top_cols"],
                                     "lattice.bottom_rows": rows * s["lattice.top_rows"]})


def _cadence(label: str, spacings: float) -> Setting:
    """Interface frames every ``spacings`` a/c_r, i.e. spacings / top_cols l/c_r."""
    return Setting(label, lambda s: {"output.interface_dt": spacings / s["lattice.top_cols"]})


KNOBS: tuple[Knob, ...] = (
    Knob("time_step", "time.safety: dt as a fraction of the stability limit 2/omega_max",
         _s("safety 0.1", time__safety=0.1),
         (_s("safety 0.9", time__safety=0.9), _s("safety 0.5", time__safety=0.5),
          _s("safety 0.25", time__safety=0.25))),
    Knob("precision", "time.precision: floating-point precision of the state",
         _s("float64", time__precision="float64"), (_s("float32", time__precision="float32"),)),
    Knob("substrate_size", "lattice.bottom_cols x bottom_rows (l = top_cols)",
         _size("5 l x 4 top_rows", 5, 4), (_size("2 l x 2 top_rows", 2, 2), _size("3 l x 2 top_rows", 3, 2))),
    Knob("substrate_model", "material.bottom_kn, lattice.substrate (reference: the paper's k_n = 100)",
         _s("k_n 100", material__bottom_kn=100.0),
         (_s("k_n 1e3", material__bottom_kn=1e3), _s("k_n 1e4", material__bottom_kn=1e4),
          _s("rigid", lattice__substrate="rigid")), limit="rigid"),
    Knob("cadence", "output.interface_dt in a/c_r (a front at c_r crosses one spacing per a/c_r)",
         _cadence("0.25 a/c_r", 0.25), (_cadence("1 a/c_r", 1.0), _cadence("2 a/c_r", 2.0), _cadence("5 a/c_r", 5.0))),
    Knob("preset", "the recommended settings (parslip.scene.presets): a quick look against publication quality",
         Setting("publication", lambda s: _preset("PUBLICATION")), (Setting("quick look", lambda s: _preset("QUICK_LOOK")),)),
)


def _preset(name: str) -> dict:
    """A preset of ``parslip.scene.presets`` as scene overrides, its interface cadence left to the study."""
    from ..scene import presets
    return {k: v for k, v in getattr(presets, name).items() if k != "output.interface_dt"}


# Drive long enough for the first three nucleations and the fronts' first stretch (l/c_r), by drive mode.
DURATION = {"push": 32.0, "pull": 32.0, "shear": 76.0}


# --- running ------------------------------------------------------------------------

@dataclass
class RunResult:
    path: str
    code: int                   # exit code of `parslip run`
    wall: float                 # s, the subprocess's wall clock
    error: str = ""             # last line of stderr when it failed
    solver: float = math.nan    # s, the time stepping alone (the run file's timing_loop_s)
    drive: float = math.nan     # s, the drive phase alone (timing_drive_s)
    drive_cpu: float = math.nan  # s, CPU time of the drive phase (timing_drive_cpu_s): robust to other jobs

    @property
    def unavailable(self) -> bool:
        return self.code == 2 and "unknown key" in self.error


def run_setting(scene: str, out: str, sets: dict, base_sets=(), repeat: int = 1) -> RunResult:
    """``parslip run scene`` with ``--set`` overrides in a subprocess, timed by wall clock.

    With ``repeat`` > 1 the run is made that many times and each time is the
    smallest seen (the least disturbed by other jobs); the output is the last run's.
    """
    best = None
    for _ in range(max(1, repeat)):
        r = _run_once(scene, out, sets, base_sets)
        if r.code != 0:
            return r
        best = r if best is None else RunResult(out, 0, min(best.wall, r.wall), "", min(best.solver, r.solver),
                                                min(best.drive, r.drive), min(best.drive_cpu, r.drive_cpu))
    return best


def _run_once(scene: str, out: str, sets: dict, base_sets=()) -> RunResult:
    from ..parallel.launcher import python_command
    items = [*base_sets, *(f"{k}={_toml(v)}" for k, v in sets.items())]
    cmd = python_command("parslip", "run", scene, "--out", out, "--overwrite", "--quiet", "--no-png",
                         *(x for s in items for x in ("--set", s)))
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    err = p.stderr.strip().splitlines()[-1] if p.returncode and p.stderr.strip() else ""
    return RunResult(out, p.returncode, wall, err, *(file_times(out) if p.returncode == 0 else
                                                      (math.nan, math.nan, math.nan)))


def file_times(path: str) -> tuple[float, float, float]:
    """(time stepping, drive phase, drive-phase CPU) in s, from the run file's timings (``io.contract``).

    The time stepping runs from the first step to the end (settling included, compilation not); the
    drive phase from the drive's first step to the end, so it leaves out start-up, compilation, the load
    ramp and settling; its CPU time (rank 0's) is what other jobs on the same cores inflate far less.
    NaN where a file holds no timing.
    """
    from ..io.contract import read_timings
    t = read_timings(path)
    return t.get("loop_s", math.nan), t.get("drive_s", math.nan), t.get("drive_cpu_s", math.nan)


def _toml(v) -> str:
    return f'"{v}"' if isinstance(v, str) else repr(v)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9.]+", "_", text).strip("_")


def study(scene: str, out_dir: str, knobs=None, quick: bool = False, duration: float | None = None,
          sets=(), repeat: int = 1) -> list[dict]:
    """Run each knob's reference and variants and measure each variant against its reference.

    ``knobs``: names to include (default all); ``quick``: only the first
    variant of each knob; ``duration``: drive time in l/c_r (default by
    drive mode, DURATION); ``sets``: further ``key=value`` overrides for every
    run; ``repeat``: runs per setting, each time the smallest (``run_setting``).
    Snapshots are off, and every knob but ``cadence`` records the interface at
    the cadence knob's finest setting, so that the other knobs' errors are not
    hidden under the frame spacing (a first-break time is known to one frame).
    Settings that resolve to the same scene share one run.  Returns one row
    per setting (the reference with zero error) with its times and the errors
    of ``metrics``, or a status of ``unavailable`` / ``failed: ...``; a knob
    with a ``limit`` adds rows of its other settings measured against it.
    """
    import json

    from ..errors import ConfigError
    from ..scene.load import load, overrides
    from ..analysis.results import open as open_run

    base = load(scene, sets)
    dur = duration or DURATION.get(base["drive.mode"], base["drive.duration"])
    fine = next(k for k in KNOBS if k.name == "cadence").reference.sets(base)
    base_over = {**fine, **dict(overrides(sets)), "drive.duration": float(dur), "output.snapshots": 0}
    base_sets = [f"{k}={_toml(v)}" for k, v in base_over.items()]
    os.makedirs(out_dir, exist_ok=True)
    done: dict[str, RunResult] = {}

    def run(label: str, over: dict) -> RunResult:
        try:                            # the resolved scene: settings that spell the same scene share a run
            key = json.dumps(load(scene, {**base_over, **over}), sort_keys=True, default=str)
        except ConfigError:
            key = json.dumps(over, sort_keys=True, default=str)
        if key not in done:
            path = os.path.join(out_dir, _slug(label) + ".vtkhdf")
            log.info(f"running {label}: {' '.join(f'{k}={v}' for k, v in over.items())}")
            done[key] = run_setting(scene, path, over, base_sets, repeat)
        return done[key]

    rows = []
    for knob in KNOBS:
        if knobs and knob.name not in knobs:
            continue
        variants = knob.variants[:1] if quick else knob.variants
        ref = run(f"{knob.name} {knob.reference.label}", knob.reference.sets(base))
        if ref.unavailable:             # the engine does not know this knob's key: no point running variants
            variants = ()
        ref_run = open_run(ref.path) if ref.code == 0 else None
        results = {}
        for setting, is_ref in [(knob.reference, True)] + [(v, False) for v in variants]:
            res = ref if is_ref else run(f"{knob.name} {setting.label}", setting.sets(base))
            results[setting.label] = res
            row = {"knob": knob.name, "setting": setting.label, "against": knob.reference.label,
                   "reference": is_ref, "wall_s": res.wall, "solver_s": res.solver, "drive_s": res.drive,
                   "drive_cpu_s": res.drive_cpu, "status": "ok"}
            if res.unavailable or (ref.unavailable and not is_ref):
                row["status"] = "unavailable (key refused)"
            elif res.code != 0 or ref_run is None:
                row["status"] = f"failed: {(res.error or ref.error)[:120]}"
            else:
                row.update(metrics(open_run(res.path), ref_run))
            row.update(provenance(res.path) if res.code == 0 else {})
            rows.append(row)
            if row["status"] != "ok":
                log.info(f"{knob.name} {setting.label}: {row['status']}")
        rows += _against_limit(knob, rows, results)
    return rows


def _against_limit(knob: Knob, rows: list[dict], results: dict) -> list[dict]:
    """Every other setting of ``knob`` measured against its ``limit`` setting, from the runs already made
    (``results``: label -> RunResult): how far each is from the limit, e.g. an elastic substrate of
    growing k_n from the rigid one.  Rows carry ``against`` = the limit's label."""
    from ..analysis.results import open as open_run
    mine = {r["setting"]: r for r in rows if r["knob"] == knob.name and r["against"] == knob.reference.label}
    if not knob.limit or mine.get(knob.limit, {}).get("status") != "ok":
        return []
    lim_run = open_run(results[knob.limit].path)
    out = []
    for label, r in mine.items():
        if label == knob.limit or r["status"] != "ok":
            continue
        row = {k: r[k] for k in ("knob", "setting", "wall_s", "solver_s", "drive_s", "drive_cpu_s", "status",
                                 "scene", "commit") if k in r}
        row.update({"against": knob.limit, "reference": False, "vs_limit": True}, **metrics(open_run(results[label].path), lim_run))
        out.append(row)
    return out


def provenance(path: str) -> dict:
    """The row's ``scene`` (the resolved scene that ran, JSON of flat dotted keys, as the sweep tables
    have it) and ``commit`` (the git commit the run file records)."""
    import json

    from ..analysis.results import open as open_run
    run = open_run(path)
    return {"scene": json.dumps(run.scene, sort_keys=True), "commit": str(run.attrs.get("git_commit", ""))}


# --- reports ------------------------------------------------------------------------

COLUMNS = ("knob", "setting", "against", "reference", "status", "wall_s", "solver_s", "drive_s",
           "drive_cpu_s") + METRICS
PROVENANCE = ("scene", "commit")          # in the CSV, not in the Markdown table
UNITS = {"wall_s": "s", "solver_s": "s", "drive_s": "s", "drive_cpu_s": "s", "first_break_t": "l/c_r", "first_break_x": "l", "interval": "rel", "speed": "rel",
         "slip": "rel", "spacetime": "fraction"}


def _cell(v) -> str:
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.4g}"
    return str(v)


def _header(c: str) -> str:
    return f"{c}_{UNITS[c]}" if c in UNITS and not c.endswith("_s") else c


def to_csv(rows: list[dict]) -> str:
    """One row per setting, with the scene that ran and its commit (quoted as CSV quotes)."""
    import csv
    import io
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([_header(c) for c in COLUMNS + PROVENANCE])
    for r in rows:
        w.writerow([_cell(r.get(c, "")) for c in COLUMNS + PROVENANCE])
    return buf.getvalue()


def from_csv(text: str) -> list[dict]:
    """The rows of an ``accuracy.csv`` (``to_csv``) back, to redraw the reports without rerunning:
    numbers as floats (an empty cell as NaN), ``reference`` as a bool, and ``vs_limit`` set on the rows
    measured against a knob's limit rather than its reference."""
    import csv
    import io
    refs = {k.name: k.reference.label for k in KNOBS}
    names = {_header(c): c for c in COLUMNS + PROVENANCE}
    rows = []
    for raw in csv.DictReader(io.StringIO(text)):
        r = {names.get(k, k): v for k, v in raw.items()}
        for c in COLUMNS[5:]:
            r[c] = float(r[c]) if r.get(c) else math.nan
        r["reference"] = r["reference"] == "True"
        r["vs_limit"] = not r["reference"] and r["against"] != refs.get(r["knob"], r["against"])
        rows.append(r)
    return rows


def to_markdown(rows: list[dict]) -> str:
    head = [f"{c} ({UNITS[c]})" if c in UNITS else c for c in COLUMNS]
    out = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(COLUMNS)]
    for r in rows:
        out.append("| " + " | ".join(_cell(r.get(c, "")) for c in COLUMNS) + " |")
    return "\n".join(out) + "\n"


PARETO = ("speed", "spacetime", "first_break_t")
FLOOR = 1e-6        # a zero error is drawn here on the log axis


def cost(row: dict) -> float:
    """The run time a row is plotted against, s: the drive phase's CPU time when the run logged it (what
    the drive costs on a core of its own; other jobs on the cores stretch the wall clock), else its wall
    time, else the whole subprocess's."""
    for k in ("drive_cpu_s", "drive_s", "wall_s"):
        if math.isfinite(row.get(k, math.nan)):
            return row[k]
    return math.nan


def pareto_png(rows: list[dict], out_dir: str, title: str = "") -> list[str]:
    """Error against run time (``cost``), one panel per metric in PARETO, one colour per knob (log-log).

    Each knob's reference is drawn hollow at the floor, unlabelled (its error is zero by definition); rows measured
    against a knob's limit instead of its reference are left out."""
    from ..plot.figures import legend, pyplot, save
    plt = pyplot()
    fig, axes = plt.subplots(1, len(PARETO), figsize=(4.2 * len(PARETO), 3.6))
    knobs = list(dict.fromkeys(r["knob"] for r in rows))
    for ax, m in zip(axes, PARETO):
        for i, kn in enumerate(knobs):
            mine = [r for r in rows if r["knob"] == kn and r["status"] == "ok" and not r.get("vs_limit")]
            ref = [r for r in mine if r["reference"]]
            pts = [(cost(r), r[m], r["setting"]) for r in mine
                   if not r["reference"] and math.isfinite(r.get(m, math.nan))]
            for r in ref:
                ax.scatter([cost(r)], [FLOOR], facecolors="none", edgecolors=f"C{i}", s=30)
            if not pts:
                continue
            ax.scatter([p[0] for p in pts], [max(p[1], FLOOR) for p in pts], color=f"C{i}", label=kn, s=18)
            for w, e, lab in pts:
                ax.annotate(lab, (w, max(e, FLOOR)), fontsize=6)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("drive-phase CPU time / s")
        ax.set_ylabel(f"{m} error ({UNITS[m]}; 0 at {FLOOR:g})")
        legend(ax, 6)
    fig.suptitle((title + ": " if title else "") + "error against run time (hollow: each knob's reference)",
                 fontsize=9)
    ok = [r for r in rows if r.get("scene")]
    return save(fig, out_dir, "accuracy_pareto", {"scene": [r["scene"] for r in ok], "commit": [r["commit"] for r in ok]})


def write_reports(rows: list[dict], out_dir: str, title: str = "") -> list[str]:
    """accuracy.csv, accuracy.md and the Pareto plot (titled ``title``) in ``out_dir``."""
    paths = [os.path.join(out_dir, "accuracy.csv"), os.path.join(out_dir, "accuracy.md")]
    with open(paths[0], "w") as fh:
        fh.write(to_csv(rows))
    with open(paths[1], "w") as fh:
        fh.write(to_markdown(rows))
    return paths + pareto_png(rows, out_dir, title)
