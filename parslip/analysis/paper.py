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


def edge_nucleations(run, min_sites: int = 5, max_gap: float = 3.0) -> list:
    """Every front nucleated at the driven edge (``edge_fronts``), counting one cut short by the end of
    the record: a front with fewer than ``min_sites`` sites counts when its tip was still advancing
    within ``max_gap`` l/c_r of the last frame (it is young, not small), e.g. the tenth pulse of the
    push scene, born at 96.4 l/c_r with three sites broken by 100."""
    edge = 1.0 if run.mode == "pull" else 0.0
    t_end = float(run.times[-1]) if len(run.times) else 0.0
    return [f for f in run.fronts(min_sites=1) if abs(f.nucleation_x - edge) < EDGE
            and (len(f.tip["x"]) >= min_sites or t_end - float(f.tip["t"][-1]) <= max_gap)]


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


def section_width(run, t: float) -> float:
    """Median length, in lattice spacings a, of the runs of broken bonds in the frame nearest ``t`` (l/c_r).

    The paper's reading of a pulse width (Sec. 3.1.1, appendix A): a constant-time
    section of the space-time map, where each pulse is one white run.  Runs
    that touch either edge of the contact are left out (a pulse being born or
    leaving).  One site is one a.  NaN when the frame has no interior run.
    """
    broken = run.interface["intact"][run.frame_at(t)] == 0
    edges = np.flatnonzero(np.diff(np.concatenate(([0], broken.astype(np.int8), [0]))))
    starts, ends = edges[::2], edges[1::2]                  # run i covers sites starts[i] .. ends[i] - 1
    keep = (starts > 0) & (ends < len(broken))
    return float(np.median(ends[keep] - starts[keep])) if keep.any() else math.nan


def far_edge_width(run) -> float:
    """Broken sites behind the first front's tip when it reaches its last site, a: the whole contact
    (l / a sites) for a crack, less for a pulse, whose bonds re-attach behind it while it runs."""
    fr = run.fronts()
    return float(fr[0].tip["w"][-1]) if fr else math.nan


def speed_ratio(pull, push, n: int = 2, how: str = "steady") -> float:
    """T+ / T- speed of the first ``n`` edge fronts: ``steady`` (``steady_speed``, the claims' reading)
    or ``mean`` (each front's mean speed over its whole run, acceleration included), both in c_r."""
    def v(run):
        fr = edge_fronts(run)[:n]
        return float(np.mean([steady_speed(f) if how == "steady" else abs(f.mean_speed) for f in fr]))
    return v(pull) / v(push)


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
          ("push",), lambda r: len(edge_nucleations(r["push"]))),
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
          ("push", "pull"), lambda r: speed_ratio(r["pull"], r["push"])),
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


# --- tests of the disagreements ------------------------------------------------------

def _unit_factor(unit: str) -> float:
    """c_ref / c_r for a reading of the paper's velocity unit: the classical Rayleigh speed (1), the
    Born lattice's own surface wave, or the shear speed; plane strain, nu = 0.2 as in every scene."""
    from ..model import physics
    r = physics.cl_over_cs(0.2, "plane_strain")
    c_r = physics.rayleigh_ratio(r)
    if unit == "born":
        kn, kt = physics.born_stiffness(r, 1.0)
        return physics.born_surface_ratio(kn, kt) / c_r
    return {"c_r": 1.0, "c_s": 1.0 / c_r}[unit]


@dataclass(frozen=True)
class Variation:
    """A run that tests one likely reason for one disagreement with the paper.

    ``sets`` (``--set`` items) change every run in ``roles`` (or, when empty,
    nothing: an analysis variation reads the baseline runs); ``measure`` reads
    the quantity from a dict of runs by role, the same way for the baseline and
    the variation; ``baseline`` (default ``measure``) reads the baseline.
    """
    name: str                       # slug, in the run files' names
    disagreement: str
    reason: str
    roles: tuple[str, ...]
    sets: tuple[str, ...]
    measure: Callable[[dict], object]
    units: str = ""
    paper: str = ""
    baseline: Callable[[dict], object] | None = None


def _scaled_first_break(unit: str):
    """The T0 first break read in l/c_ref, for a run driven at 1e-4 c_ref (c_ref from ``_unit_factor``)."""
    return lambda r: first_break_time(r["shear"]) * _unit_factor(unit)


def _v0_in(unit: str) -> str:
    return f"drive.v0={float(1e-4 * _unit_factor(unit))!r}"


_T0_BREAK = "T0 first break 70.0 vs the paper's 65.37 l/c_r"
_T0_KIND = "T0 front: a wide pulse, not a crack"
_RATIO = "T+ / T- pulse speed 0.89 vs the paper's 0.5"
_WIDTH = "T- pulse width ~4 a vs the paper's ~1 a"

VARIATIONS: list[Variation] = [
    Variation("bottom200", _T0_BREAK, "substrate 200 columns (the methods text) instead of 300 (the captions)",
              ("shear",), ("lattice.bottom_cols=200",), lambda r: first_break_time(r["shear"]), "l/c_r", "65.37"),
    Variation("units_born", _T0_BREAK, "velocity unit = the Born lattice's own surface wave (0.9475 c_s): "
              "v0 = 1e-4 of it, times read in l over it", ("shear",), (_v0_in("born"),),
              _scaled_first_break("born"), "l/c_ref", "65.37", baseline=lambda r: first_break_time(r["shear"])),
    Variation("units_cs", _T0_BREAK, "velocity unit = c_s: v0 = 1e-4 c_s, times read in l/c_s",
              ("shear",), (_v0_in("c_s"),), _scaled_first_break("c_s"), "l/c_ref", "65.37",
              baseline=lambda r: first_break_time(r["shear"])),
    Variation("zeta0", _T0_BREAK, "no damping (zeta = 0)", ("shear",), ("time.zeta=0.0",),
              lambda r: first_break_time(r["shear"]), "l/c_r", "65.37"),
    Variation("zeta0.05", _T0_BREAK, "damping zeta halved (0.05)", ("shear",), ("time.zeta=0.05",),
              lambda r: first_break_time(r["shear"]), "l/c_r", "65.37"),
    Variation("zeta0.2", _T0_BREAK, "damping zeta doubled (0.2)", ("shear",), ("time.zeta=0.2",),
              lambda r: first_break_time(r["shear"]), "l/c_r", "65.37"),
    Variation("fn_per_node", _T0_BREAK, "F_N = 1 on every node of SR (total 100) instead of 1 in all",
              ("shear",), ("load.FN=100.0",), lambda r: first_break_time(r["shear"]), "l/c_r", "65.37"),
    Variation("plane_stress", _T0_BREAK, "nu = 0.2 read as plane stress (c_l/c_s = sqrt(2/(1-nu))), not plane strain",
              ("shear",), ('material.model="plane_stress"',), lambda r: first_break_time(r["shear"]), "l/c_r",
              "65.37"),
    Variation("reform_zero", _T0_BREAK, "a re-formed bond's rest offset 0 instead of its offset when it forms",
              ("shear",), ('interface.reform_x0="zero"',), lambda r: first_break_time(r["shear"]), "l/c_r",
              "65.37"),
    Variation("rigid", _T0_BREAK, "a rigid substrate (k_n -> infinity: 'comparatively rigid')",
              ("shear",), ('lattice.substrate="rigid"',), lambda r: first_break_time(r["shear"]), "l/c_r",
              "65.37"),
    Variation("fine_cadence", _T0_KIND, "interface cadence 0.25 a/c_r instead of 1 a/c_r",
              ("shear",), ("output.interface_dt=0.0025",), lambda r: far_edge_width(r["shear"]), "a",
              "100 (crack: all bonds broken when it reaches x/l = 1)"),
    Variation("zeta0", _T0_KIND, "no damping (zeta = 0)", ("shear",), ("time.zeta=0.0",),
              lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("zeta0.01", _T0_KIND, "damping zeta / 10 (0.01)", ("shear",), ("time.zeta=0.01",),
              lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("zeta0.05", _T0_KIND, "damping zeta halved (0.05)", ("shear",), ("time.zeta=0.05",),
              lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("zeta0.2", _T0_KIND, "damping zeta doubled (0.2)", ("shear",), ("time.zeta=0.2",),
              lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("bottom200", _T0_KIND, "substrate 200 columns", ("shear",), ("lattice.bottom_cols=200",),
              lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("rigid", _T0_KIND, "a rigid substrate", ("shear",), ('lattice.substrate="rigid"',),
              lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("fn_per_node", _T0_KIND, "F_N = 1 per node (total 100)", ("shear",), ("load.FN=100.0",),
              lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("plane_stress", _T0_KIND, "nu = 0.2 read as plane stress", ("shear",),
              ('material.model="plane_stress"',), lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("reform_zero", _T0_KIND, "a re-formed bond's rest offset 0", ("shear",),
              ('interface.reform_x0="zero"',), lambda r: far_edge_width(r["shear"]), "a", "100"),
    Variation("mean_speed", _RATIO, "speed read as each pulse's mean over its whole run, not its steady stretch",
              ("push", "pull"), (), lambda r: speed_ratio(r["pull"], r["push"], how="mean"), "", "0.5",
              baseline=lambda r: speed_ratio(r["pull"], r["push"])),
    Variation("bottom200", _RATIO, "substrate 200 columns", ("push", "pull"), ("lattice.bottom_cols=200",),
              lambda r: speed_ratio(r["pull"], r["push"]), "", "0.5"),
    Variation("zeta0.2", _RATIO, "damping zeta doubled (0.2)", ("push", "pull"), ("time.zeta=0.2",),
              lambda r: speed_ratio(r["pull"], r["push"]), "", "0.5"),
    Variation("fn_per_node", _RATIO, "F_N = 1 per node (total 100): more compression at the nucleation site",
              ("push", "pull"), ("load.FN=100.0",), lambda r: speed_ratio(r["pull"], r["push"]), "", "0.5"),
    Variation("fn2", _RATIO, "F_N doubled (2 in all)", ("push", "pull"), ("load.FN=2.0",),
              lambda r: speed_ratio(r["pull"], r["push"]), "", "0.5"),
    Variation("plane_stress", _RATIO, "nu = 0.2 read as plane stress", ("push", "pull"),
              ('material.model="plane_stress"',), lambda r: speed_ratio(r["pull"], r["push"]), "", "0.5"),
    Variation("reform_zero", _RATIO, "a re-formed bond's rest offset 0 (pre-stressed) instead of its offset "
              "when it forms", ("push", "pull"), ('interface.reform_x0="zero"',),
              lambda r: speed_ratio(r["pull"], r["push"]), "", "0.5"),
    Variation("section_t30", _WIDTH, "width read as the paper does: white runs in the section t c_r/l = 30",
              ("push",), (), lambda r: section_width(r["push"], 30.0), "a", "~1",
              baseline=lambda r: steady_width(r["push"])),
    Variation("fine_cadence", _WIDTH, "interface cadence 0.25 a/c_r instead of 1 a/c_r", ("push",),
              ("output.interface_dt=0.0025",), lambda r: steady_width(r["push"]), "a", "~1"),
    Variation("zeta0.2", _WIDTH, "damping zeta doubled (0.2)", ("push",), ("time.zeta=0.2",),
              lambda r: steady_width(r["push"]), "a", "~1"),
    Variation("fn_per_node", _WIDTH, "F_N = 1 per node (total 100)", ("push",), ("load.FN=100.0",),
              lambda r: steady_width(r["push"]), "a", "~1"),
    Variation("bottom200", _WIDTH, "substrate 200 columns", ("push",), ("lattice.bottom_cols=200",),
              lambda r: steady_width(r["push"]), "a", "~1"),
    Variation("reform_zero", _WIDTH, "a re-formed bond's rest offset 0 instead of its offset when it forms",
              ("push",), ('interface.reform_x0="zero"',), lambda r: steady_width(r["push"]), "a", "~1"),
    Variation("zeta0", _WIDTH, "no damping (zeta = 0)", ("push",), ("time.zeta=0.0",),
              lambda r: steady_width(r["push"]), "a", "~1"),
    Variation("plane_stress", _WIDTH, "nu = 0.2 read as plane stress", ("push",),
              ('material.model="plane_stress"',), lambda r: steady_width(r["push"]), "a", "~1"),
]


def _measure(fn, runs: dict) -> str:
    try:
        return _fmt(fn(runs))
    except (IndexError, ValueError, ZeroDivisionError, KeyError) as e:      # too few fronts, a failed run
        return f"n/a ({type(e).__name__})"


def variation_path(run_dir: str, v: Variation, role: str) -> str:
    return os.path.join(run_dir, "variations", f"{role}__{v.name}.vtkhdf")


def run_variations(runs: dict, run_dir: str, scene_dir: str = "run", run_missing: bool = False,
                    ranks: int = 1, variations=None) -> list[dict]:
    """Each variation's quantity for the baseline runs and for the varied ones (made with ``run_missing``
    as ``run_dir/variations/<role>__<name>.vtkhdf``; a run made once serves every variation that shares
    its name and role).  Rows: disagreement, reason, change, units, paper, baseline, varied."""
    from .results import open as open_run
    rows = []
    for v in variations or VARIATIONS:
        if any(role not in runs for role in v.roles):
            continue
        varied, failed = dict(runs), ""
        for role in (v.roles if v.sets else ()):
            path = variation_path(run_dir, v, role)
            if not os.path.exists(path) and run_missing:
                os.makedirs(os.path.dirname(path), exist_ok=True)
                log.info(f"variation {v.name}: {role} with {' '.join(v.sets)}")
                code = run_scene(os.path.join(scene_dir, SCENES[role]), path, ranks, v.sets)
                if code != 0:
                    failed = f"run failed (exit {code})"
            if os.path.exists(path) and not failed:
                varied[role] = open_run(path)
            else:
                failed = failed or "not run"
        rows.append({"disagreement": v.disagreement, "reason": v.reason,
                     "change": " ".join(v.sets) or "(analysis only)", "units": v.units, "paper": v.paper,
                     "baseline": _measure(v.baseline or v.measure, runs),
                     "varied": failed or _measure(v.measure, varied)})
    return rows


def variations_markdown(rows: list[dict]) -> str:
    """The variations as a Markdown table."""
    keys = ("disagreement", "reason", "change", "units", "paper", "baseline", "varied")
    out = ["| disagreement | reason tested | change | units | paper | parslip | with the change |",
           "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        out.append("| " + " | ".join(str(r[k]).replace("|", "\\|") for k in keys) + " |")
    return "\n".join(out) + "\n"


# --- the runs -----------------------------------------------------------------------

SCENES = {                  # role -> scene file under run/
    "push": "push.toml", "pull": "pull.toml", "shear": "shear.toml",
    "push_v0_1e-2": "push_v0_1e-2.toml", "push_v0_1e-4": "push_v0_1e-4.toml",
    "shear_maps": "shear.toml",
}
# Roles that are a scene with overrides.  shear_maps: the T0 rupture crosses the contact in about
# 1.5 l/c_r, and the shear scene's snapshots are 4 l/c_r apart; this run stops at 72 l/c_r with a
# snapshot every 0.5 l/c_r (about 200 MB), for the stress maps of Fig. 7a.
ROLE_SETS = {"shear_maps": ("drive.duration=72.0", "output.snapshots=144")}
MAPS_ONLY = {"shear_maps": "shear"}     # role -> the role whose stress maps it draws (no figure set of its own)


def run_scene(scene: str, out: str, ranks: int = 1, sets=()) -> int:
    """``parslip run scene --out out`` in a subprocess (under mpiexec for ranks > 1); returns its exit code."""
    from ..parallel.launcher import python_command
    sets = [x for s in sets for x in ("--set", s)]
    cmd = python_command("parslip", "run", scene, "--out", out, "--overwrite", "--quiet", *sets,
                         ranks=ranks if ranks > 1 else None)
    return subprocess.run(cmd).returncode


def reproduce(run_dir: str, out_dir: str, scene_dir: str = "run", run_missing: bool = False,
              ranks: int = 1, roles=None, variations: bool = False) -> dict:
    """Find (or, with ``run_missing``, make) each role's run as ``run_dir/<role>.vtkhdf``, then write each
    run's figure set under ``out_dir/<role>/``, the v0-sweep and push/pull comparisons and
    ``out_dir/comparison.md``; with ``variations``, also the runs that test each disagreement's likely
    reason (``VARIATIONS``) and ``out_dir/variations.md``.  Returns the runs found."""
    from . import figures
    from .results import open as open_run

    os.makedirs(out_dir, exist_ok=True)
    runs = {}
    for role in roles or SCENES:
        path = os.path.join(run_dir, f"{role}.vtkhdf")
        if not os.path.exists(path) and run_missing:
            log.info(f"running {role}: {SCENES[role]} -> {path}")
            if run_scene(os.path.join(scene_dir, SCENES[role]), path, ranks, ROLE_SETS.get(role, ())) != 0:
                log.warning(f"{role}: the run failed; left out")
                continue
        if os.path.exists(path):
            runs[role] = open_run(path)
        else:
            log.info(f"{role}: no {path}; left out (pass --run to make it)")
    for role, run in runs.items():
        if role not in MAPS_ONLY:
            figures.write_all(run, os.path.join(out_dir, role))
    for role, of in MAPS_ONLY.items():       # denser snapshots of the same scene, at the times its run asks for
        if role in runs and of in runs:
            figures.fig_stress_maps(runs[role], os.path.join(out_dir, of), times=figures.map_times(runs[of]))
    sweep = [runs[k] for k in ("push_v0_1e-2", "push", "push_v0_1e-4") if k in runs]
    if len(sweep) > 1:
        figures.compare_speeds(sweep, out_dir, scale="v0", name="v0_sweep")
    if "push" in runs and "pull" in runs:
        figures.compare_speeds([runs["push"], runs["pull"]], out_dir, n=2, scale="c_r", name="push_vs_pull")
    with open(os.path.join(out_dir, "comparison.md"), "w") as fh:
        fh.write(markdown(comparison(runs)))
    if variations:
        rows = run_variations(runs, run_dir, scene_dir, run_missing, ranks)
        with open(os.path.join(out_dir, "variations.md"), "w") as fh:
            fh.write(variations_markdown(rows))
    return runs
