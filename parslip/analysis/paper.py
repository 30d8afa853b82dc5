"""The paper reproduced: its quantitative statements beside parslip's measurements, and the runs behind them.

Responsible for (1) CLAIMS, each of the paper's quantitative statements with
the paper's value, where in the .tex it comes from, the run it needs and how
parslip measures it from that run; (2) ``comparison`` / ``markdown``, which
turn a set of runs into the comparison table (Markdown); (3) SCENES and
``reproduce``, which run or find those runs and write every figure set,
the comparisons and the table (``postprocess/paper.py`` is a thin wrapper).

Runs are keyed by role: ``push``, ``pull``, ``shear`` (the three shipped
scenes) and ``push_v0_1e-2``, ``push_v0_1e-4`` (the v0 sweep of Fig. 2d;
``push`` is v0/c_r = 1e-3).  Units: t in l/c_r, x and slip in l, speeds in
c_r, widths in lattice spacings a.
"""
from __future__ import annotations

import logging
import math
import os
import subprocess
import sys
from dataclasses import dataclass
from typing import Callable

import numpy as np

log = logging.getLogger("parslip")

EDGE = 0.05          # l: a front "nucleates at the driven edge" within this distance of it
STEADY = (0.1, 0.6)  # x_tip/l range where pulses run at their steady speed (they accelerate past ~0.7)


# --- measurements -------------------------------------------------------------------

def edge_fronts(run) -> list:
    """Fronts nucleated at the edge the run's drive loads first: x = 0 for push and shear, 1 for pull."""
    edge = 1.0 if run.mode == "pull" else 0.0
    return [f for f in run.fronts() if abs(f.nucleation_x - edge) < EDGE]


def nucleation_times(run, n: int = 4) -> list[float]:
    return [f.nucleation_time for f in edge_fronts(run)[:n]]


def interval(run) -> float:
    """Mean time between successive nucleations at the driven edge, l/c_r."""
    t = [f.nucleation_time for f in edge_fronts(run)]
    return float(np.mean(np.diff(t))) if len(t) > 1 else math.nan


def steady_speed(front, lo: float = STEADY[0], hi: float = STEADY[1]) -> float:
    """Median |v|/c_r of a front while its distance from its nucleation site is within [lo, hi] l."""
    d = np.abs(front.tip["x"] - front.nucleation_x)
    v = np.abs(front.tip["v"][(d >= lo) & (d <= hi)])
    return float(np.median(v)) if len(v) else math.nan


def mean_steady_speed(run, n: int = 3) -> float:
    """Mean of ``steady_speed`` over the first ``n`` edge fronts, c_r."""
    v = [steady_speed(f) for f in edge_fronts(run)[:n]]
    v = [x for x in v if math.isfinite(x)]
    return float(np.mean(v)) if v else math.nan


def first_break_time(run) -> float:
    from .fronts import first_break
    t, _ = first_break(run.interface)
    return math.nan if t is None else t


def crack_speed(run) -> float:
    """Median |v|/c_r of the first front once its tip is past x/l = 0.2."""
    fr = run.fronts()
    if not fr:
        return math.nan
    f = fr[0]
    v = np.abs(f.tip["v"][np.abs(f.tip["x"] - f.nucleation_x) > 0.2])
    return float(np.median(v)) if len(v) else math.nan


def median_slip(run, n: int = 4) -> float:
    """Median over the first ``n`` fronts of the slip u each carries, l."""
    s = [f.slip_u for f in run.fronts()[:n] if math.isfinite(f.slip_u)]
    return float(np.median(s)) if s else math.nan


def steady_width(run, n: int = 4) -> float:
    """Median width (a) of the first ``n`` edge fronts over their steady stretch."""
    w = []
    for f in edge_fronts(run)[:n]:
        d = np.abs(f.tip["x"] - f.nucleation_x)
        w += list(f.tip["w"][(d >= STEADY[0]) & (d <= STEADY[1])])
    return float(np.median(w)) if w else math.nan


def _fmt(v) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, (list, tuple)):
        return ", ".join(_fmt(x) for x in v) if v else "none"
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.3g}"


# --- the claims ---------------------------------------------------------------------

@dataclass(frozen=True)
class Claim:
    quantity: str
    paper: str                      # the paper's value, as it states it
    source: str                     # where in onset-of-slip.tex
    needs: tuple[str, ...]          # run roles the measurement reads
    measure: Callable[[dict], object]
    units: str = ""


def _v0_sweep(runs) -> str:
    vals = [mean_steady_speed(runs[k]) / runs[k].v0 for k in ("push_v0_1e-2", "push", "push_v0_1e-4")]
    ok = [v for v in vals if math.isfinite(v)]
    spread = max(ok) / min(ok) if len(ok) > 1 else math.nan
    return f"v/v0 = {_fmt(vals)} (max/min {_fmt(spread)})"


def _kinds(run) -> str:
    k = [f.kind for f in run.fronts()]
    return f"{k.count('pulse')} pulse, {k.count('crack')} crack" if k else "no front"


def _directions(run) -> str:
    fr = edge_fronts(run)
    d = sorted({f.direction for f in fr})
    x = [f.nucleation_x for f in fr]
    return f"x/l = {_fmt(float(np.median(x)))}, direction {d}" if fr else "no front at the edge"


CLAIMS: list[Claim] = [
    Claim("T- first four nucleation times", "5.1, 15.1, 25.2, 35.1", "Fig. 3 caption; Sec. 3.1.3",
          ("push",), lambda r: nucleation_times(r["push"]), "l/c_r"),
    Claim("T- nucleation site and direction", "x/l = 0, toward x/l = 1", "Sec. 3.1, Fig. 2b",
          ("push",), lambda r: _directions(r["push"])),
    Claim("T- pulse interval", "10.0 (from the Fig. 3 times); nearly constant", "Fig. 3 caption; Sec. 3.1.1",
          ("push",), lambda r: interval(r["push"]), "l/c_r"),
    Claim("T- pulses in 100 l/c_r", "10", "Sec. 3.1.1 (\"ten such pulses\")",
          ("push",), lambda r: len(edge_fronts(r["push"]))),
    Claim("T- steady pulse speed", "<< 1 (Fig. 2c inset)", "Sec. 3.1.1-3.1.2",
          ("push",), lambda r: mean_steady_speed(r["push"]), "c_r"),
    Claim("T- leading pulse starts to accelerate at", "x/l ~ 0.7-0.8", "Sec. 3.1.1 (0.7), Sec. 3.1.2 (~0.8 l)",
          ("push",), lambda r: edge_fronts(r["push"])[0].accel_x if edge_fronts(r["push"]) else math.nan, "l"),
    Claim("T- pulse speed proportional to v0 (v0/c_r = 1e-2, 1e-3, 1e-4)", "v/v0 curves coincide",
          "Sec. 3.1.2, Fig. 2d", ("push_v0_1e-2", "push", "push_v0_1e-4"), _v0_sweep),
    Claim("T- kind of front", "pulse (bonds re-attach behind the tip)", "Sec. 3.1",
          ("push",), lambda r: _kinds(r["push"])),
    Claim("T- pulse width", "~1 a (w/l = 0.01), widening near the far edge", "Appendix A",
          ("push",), lambda r: steady_width(r["push"]), "a"),
    Claim("T- slip per pulse", "~0.04 l to 0.011 l, constant per pulse", "Sec. 3.4",
          ("push",), lambda r: median_slip(r["push"]), "l"),
    Claim("T- net vertical displacement after a pulse", "0 (bodies re-adhere)", "Sec. 3.4, Fig. 9b",
          ("push",), lambda r: float(np.median([f.slip_v for f in r["push"].fronts()[:4]])), "l"),
    Claim("T+ first four nucleation times", "5.4, 15.5, 25.7, 35.7", "Fig. 5 caption",
          ("pull",), lambda r: nucleation_times(r["pull"]), "l/c_r"),
    Claim("T+ nucleation site and direction", "x/l = 1, toward x/l = 0", "Sec. 3.2, Fig. 4b",
          ("pull",), lambda r: _directions(r["pull"])),
    Claim("T+ pulse interval", "10.1 (from the Fig. 5 times)", "Fig. 5 caption",
          ("pull",), lambda r: interval(r["pull"]), "l/c_r"),
    Claim("T+ / T- pulse speed (first two pulses)", "0.5 (\"50% slower in pulling\")", "Appendix D",
          ("push", "pull"), lambda r: (np.mean([steady_speed(f) for f in edge_fronts(r["pull"])[:2]])
                                       / np.mean([steady_speed(f) for f in edge_fronts(r["push"])[:2]]))),
    Claim("T0 first break", "65.37", "Sec. 3.3.3", ("shear",), lambda r: first_break_time(r["shear"]), "l/c_r"),
    Claim("T0 nucleation site and direction", "x/l = 0, toward x/l = 1", "Sec. 3.3, Fig. 6b",
          ("shear",), lambda r: _directions(r["shear"])),
    Claim("T0 front speed past x_tip/l = 0.2", "~1 (0.7-1, lattice discreteness), never supershear",
          "Sec. 3.3.2, Fig. 6c", ("shear",), lambda r: crack_speed(r["shear"]), "c_r"),
    Claim("T0 kind of front", "crack (re-attachment only after it crossed)", "Sec. 3.3.1",
          ("shear",), lambda r: _kinds(r["shear"])),
    Claim("slip per front, T- / T0", "1.25 (\"almost 25% larger\" in the pulse case)", "Sec. 3.4",
          ("push", "shear"), lambda r: median_slip(r["push"]) / median_slip(r["shear"])),
]


def comparison(runs: dict) -> list[dict]:
    """One row per claim: quantity, units, the paper's value, parslip's, the source; 'not run' when a run is missing."""
    rows = []
    for c in CLAIMS:
        missing = [k for k in c.needs if k not in runs]
        if missing:
            measured = f"not run ({', '.join(missing)})"
        else:
            try:
                measured = _fmt(c.measure(runs))
            except (IndexError, ValueError, ZeroDivisionError) as e:   # too few fronts in the run
                measured = f"n/a ({type(e).__name__})"
        rows.append({"quantity": c.quantity, "units": c.units, "paper": c.paper, "parslip": measured,
                     "source": c.source})
    return rows


def markdown(rows: list[dict]) -> str:
    """The comparison as a Markdown table."""
    out = ["| quantity | units | paper | parslip | where in the paper |", "| --- | --- | --- | --- | --- |"]
    for r in rows:
        cells = [str(r[k]).replace("|", "\\|") for k in ("quantity", "units", "paper", "parslip", "source")]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


# --- the runs -----------------------------------------------------------------------

SCENES = {                  # role -> scene file under run/
    "push": "push.toml", "pull": "pull.toml", "shear": "shear.toml",
    "push_v0_1e-2": "push_v0_1e-2.toml", "push_v0_1e-4": "push_v0_1e-4.toml",
}


def run_scene(scene: str, out: str, ranks: int = 1, sets=()) -> int:
    """``parslip run scene --out out`` in a subprocess (under mpiexec for ranks > 1); returns its exit code."""
    cmd = [sys.executable, "-m", "parslip", "run", scene, "--out", out, "--overwrite", "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    return subprocess.run(cmd).returncode


def reproduce(run_dir: str, out_dir: str, scene_dir: str = "run", run_missing: bool = False,
              ranks: int = 1, roles=None) -> dict:
    """Find (or, with ``run_missing``, make) each role's run as ``run_dir/<role>.vtkhdf``, then write each
    run's figure set under ``out_dir/<role>/``, the v0-sweep and push/pull comparisons and
    ``out_dir/comparison.md``.  Returns the runs found."""
    from . import figures
    from .results import open as open_run

    os.makedirs(out_dir, exist_ok=True)
    runs = {}
    for role in roles or SCENES:
        path = os.path.join(run_dir, f"{role}.vtkhdf")
        if not os.path.exists(path) and run_missing:
            log.info(f"running {role}: {SCENES[role]} -> {path}")
            if run_scene(os.path.join(scene_dir, SCENES[role]), path, ranks) != 0:
                log.warning(f"{role}: the run failed; left out")
                continue
        if os.path.exists(path):
            runs[role] = open_run(path)
        else:
            log.info(f"{role}: no {path}; left out (pass --run to make it)")
    for role, run in runs.items():
        figures.write_all(run, os.path.join(out_dir, role))
    sweep = [runs[k] for k in ("push_v0_1e-2", "push", "push_v0_1e-4") if k in runs]
    if len(sweep) > 1:
        figures.compare_speeds(sweep, out_dir, scale="v0", name="v0_sweep")
    if "push" in runs and "pull" in runs:
        figures.compare_speeds([runs["push"], runs["pull"]], out_dir, n=2, scale="c_r", name="push_vs_pull")
    with open(os.path.join(out_dir, "comparison.md"), "w") as fh:
        fh.write(markdown(comparison(runs)))
    return runs
