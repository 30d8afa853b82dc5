"""Precursors longer than their process zone (docs/studies/cracks.md, section 2).

The push through a soft loader (``drive.spring``) at three loading heights (``drive.rows``), two normal loads
and both readings of a re-formed bond's rest offset (``interface.reform_x0`` "zero" and "current"), swept by
``run/studies/cracks_precursors*.toml``.  For every run: each arrested front (``run.precursors()`` with the
detector's patience ``max_gap`` = 300 a/c_r, as on l = 100), its
length in units of Lambda (``analysis.cracks.process_zone``, the Palmer-Rice length), F_T/F_N at its arrest
(mu at the first frame after its tip's last advance) and the arrest fracture mechanics predicts for it
(``analysis.arrest.arrest_prediction``).  Per reading, height, re-formation delay (``interface.heal_time``,
swept by ``cracks_precursors_heal.toml``) and normal load, the straight line L/Lambda = slope * F_T/F_N +
intercept through its precursors, with its r^2: Katano et al. (2014) find one line per regime whatever the
height, but a line that moves with the normal load (their Fig. 2c), and Rubinstein et al. (2007) one per
loading configuration, so the loads are fitted apart.  ``refit`` draws the fits again from the tables alone.

Tables: ``cracks_precursors.csv`` a row per run (``n_precursors``, ``min_length_over_lambda``, the height's
``slope`` and ``r2``), ``cracks_precursors_arrests.csv`` a row per precursor (measured and predicted
length); figures ``img/cracks_precursors_length.png`` (length against F_T/F_N) and
``img/cracks_precursors_prediction.png`` (predicted against measured).
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis import table
from parslip.analysis.arrest import arrest_prediction
from parslip.analysis.cracks import process_zone
from parslip.plot.figures import pyplot, save

from . import points, provenance, sweeps, write

# The readings this study departs from the defaults in, named so that the tables declare them: the matched
# pair's substrate stiffness, the damping's form and rate, the contact under unbonded sites.
READING_COLS = ["bottom_kn", "damping", "zeta", "contact"]
RUN_COLS = ["sweep", "point", "reading", "F_N", "height", "rows", "heal_time", "n_fronts", "n_crossed", "n_merged",
            "n_precursors",
            "n_from_edge", "n_over_3_lambda", "min_length_over_lambda", "max_length_over_lambda",
            "median_width_over_lambda", "Lambda", "slope", "intercept", "r2", "n_fit",
            "median_pred_over_measured"] + READING_COLS
ARREST_COLS = ["sweep", "point", "reading", "F_N", "height", "heal_time", "precursor", "kind", "from_edge",
               "geometry", "nucleation_x",
               "arrest_time", "mu_arrest", "length_over_lambda", "width_over_lambda", "predicted_over_lambda",
               "G_over_Gamma_at_arrest", "tau_r", "Gamma"] + READING_COLS
HEIGHTS = ("low", "mid", "high", "face")
# The front detector's patience in a/c_r: its default (``fronts.MAX_GAP`` = 3 l/c_r) was set on l = 100 a; on a
# longer contact the same 300 a/c_r keeps a slow tip's pause (one site at 0.01 c_r takes 100 a/c_r) one
# front, where 3 l/c_r of l = 500 would count a precursor that the next front overran within 1500 a/c_r
# (five precursor periods) as merged into it.
PATIENCE = 300.0


def max_gap(run) -> float:
    """The detector's patience for ``run`` (l/c_r): ``PATIENCE`` a/c_r over its contact of l = sites * a."""
    return PATIENCE / len(run.x)


def height_of(rows, top_rows: int) -> str:
    """The loading height's name: "face" for the whole face, else by the middle of the driven rows'
    band: the lowest, middle or highest third of the block."""
    if not rows:
        return "face"
    mid = 0.5 * (rows[0] + rows[-1]) / max(top_rows - 1, 1)
    return "low" if mid < 1 / 3 else ("mid" if mid < 2 / 3 else "high")


def _mu_at(run, time: float) -> float:
    t, mu = np.asarray(run.interface["t"], float), np.asarray(run.interface["mu"], float)
    return float(mu[min(int(np.searchsorted(t, time, side="right")), len(t) - 1)])


def run_arrests(row, run) -> tuple[dict, list[dict]]:
    """The run's row (without the fit) and a row per precursor."""
    s = run.scene
    lam = process_zone(run)
    ns = len(run.x)
    head = {"sweep": row.get("sweep", ""), "point": row["point"], "reading": s["interface.reform_x0"],
            "F_N": float(s["load.FN"]), "heal_time": float(s["interface.heal_time"]),
            "height": height_of(s["drive.rows"], int(s["lattice.top_rows"])),
            "rows": "-".join(str(r) for r in s["drive.rows"]) or "all", "scene": row["scene"],
            "commit": row["commit"], "bottom_kn": s["material.bottom_kn"], "damping": s["time.damping"],
            "zeta": s["time.zeta"], "contact": s["interface.contact"]}
    fr = run.fronts(max_gap=max_gap(run))
    arrests = []
    for i, p in enumerate(run.precursors(max_gap=max_gap(run))):
        pred = arrest_prediction(run, p)
        arrests.append({**head, "precursor": i, "kind": p.kind, "nucleation_x": p.nucleation_x,
                        "arrest_time": p.arrest_time,
                        "mu_arrest": _mu_at(run, p.arrest_time), "length_over_lambda": p.arrest_length * ns / lam,
                        "width_over_lambda": p.front.width / lam,
                        "predicted_over_lambda": pred["L_predicted"] / lam,
                        "G_over_Gamma_at_arrest": pred["G_at_arrest_over_Gamma"], "tau_r": pred["tau_r"],
                        "Gamma": pred["Gamma"], "from_edge": pred["from_edge"],
                        "geometry": pred["geometry"]})
    L = [a["length_over_lambda"] for a in arrests]
    ratio = [a["predicted_over_lambda"] / a["length_over_lambda"] for a in arrests
             if math.isfinite(a["predicted_over_lambda"])]
    nan = math.nan
    out = {**head, "n_fronts": len(fr), "n_crossed": sum(f.fate == "crossed" for f in fr),
           "n_merged": sum(f.fate == "merged" for f in fr), "n_over_3_lambda": sum(x > 3.0 for x in L),
           "n_precursors": len(arrests), "n_from_edge": sum(a["from_edge"] for a in arrests),
           "min_length_over_lambda": min(L) if L else nan, "max_length_over_lambda": max(L) if L else nan,
           "median_width_over_lambda": float(np.median([a["width_over_lambda"] for a in arrests])) if arrests else nan,
           "Lambda": lam, "median_pred_over_measured": float(np.median(ratio)) if ratio else nan}
    return out, arrests


def line_fit(x, y) -> dict:
    """Least squares y = slope x + intercept with r^2; NaN with fewer than 3 points or no spread in x."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if len(x) < 3 or np.ptp(x) == 0:
        return {"slope": math.nan, "intercept": math.nan, "r2": math.nan, "n_fit": len(x)}
    slope, icpt = np.polyfit(x, y, 1)
    res = y - (slope * x + icpt)
    ss = float(np.sum((y - y.mean()) ** 2))
    return {"slope": float(slope), "intercept": float(icpt), "r2": 1.0 - float(np.sum(res ** 2)) / ss if ss else
            math.nan, "n_fit": len(x)}


def group(a: dict) -> tuple:
    """What one fit spans: a reading, a height, a re-formation delay and a normal load."""
    return a["reading"], a["height"], a["heal_time"], a["F_N"]


def fits(arrests: list[dict]) -> dict:
    """``group`` -> ``line_fit`` of length_over_lambda against mu_arrest."""
    keys = sorted({group(a) for a in arrests})
    return {k: line_fit([a["mu_arrest"] for a in arrests if group(a) == k],
                        [a["length_over_lambda"] for a in arrests if group(a) == k]) for k in keys}


def length_figure(arrests, fit, img, source):
    """Arrest length over Lambda against F_T/F_N at the arrest, a panel per reading, a colour per loading height
    (and delay), a marker per normal load, and the line ``fits`` gives each (reading, height, delay, F_N)."""
    plt = pyplot()
    readings = sorted({a["reading"] for a in arrests}) or ["current", "zero"]
    fig, axes = plt.subplots(1, len(readings), figsize=(5 * len(readings), 4), squeeze=False)
    colors = dict(zip(HEIGHTS, ("C0", "C1", "C2", "C3")))
    loads = sorted({a["F_N"] for a in arrests})
    marks = dict(zip(loads, "os^D"))
    for ax, rd in zip(axes[0], readings):
        mine = [a for a in arrests if a["reading"] == rd]
        for k, ((r, h, ht, fn), f) in enumerate(fit.items()):
            if r != rd:
                continue
            sel = [a for a in mine if group(a) == (r, h, ht, fn)]
            c = colors[h] if ht == 0 else f"C{4 + k % 6}"
            name = (h if ht == 0 else f"{h}, heal_time {ht:g}") + f", F_N = {fn:g}"
            filled = fn == loads[-1]
            ax.plot([a["mu_arrest"] for a in sel], [a["length_over_lambda"] for a in sel], marks[fn], color=c,
                    mfc=c if filled else "none", label=name)
            if math.isfinite(f["slope"]):            # each load's own line: solid at the largest, dashed below
                xs = np.linspace(min(a["mu_arrest"] for a in sel), max(a["mu_arrest"] for a in sel), 50)
                ys = f["slope"] * xs + f["intercept"]
                ax.plot(xs[ys > 0], ys[ys > 0], "-" if filled else "--", color=c, lw=0.8)
        ax.axhline(3.0, color="k", ls=":", lw=0.8)
        ax.set_yscale("log")
        if not mine:
            ax.text(0.5, 0.5, "no front arrested inside the contact", ha="center", va="center",
                    transform=ax.transAxes)
        else:
            ax.legend(fontsize=6)
        ax.set_xlabel("F_T / F_N at the arrest")
        ax.set_ylabel("arrest length / Lambda")
        ax.set_title(f'reform_x0 = "{rd}": {len(mine)} precursors, a line per F_N (filled, solid: F_N = '
                     f'{loads[-1]:g}; dotted: 3 Lambda)' if loads else f'reform_x0 = "{rd}"', fontsize=8)
    return save(fig, img, "cracks_precursors_length", source)


def prediction_figure(arrests, img, source):
    """Left: the predicted arrest against the measured one, where G reached Gamma; right: G/Gamma at the
    measured arrest for every precursor (LEFM puts it at 1).  Filled: edge cracks; open: interior ones."""
    plt = pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(9, 4))
    pts = [a for a in arrests if math.isfinite(a["predicted_over_lambda"])]
    for rd, mk, c in (("current", "o", "C0"), ("zero", "s", "C1")):
        for geo, fill in (("edge", c), ("interior", "none")):
            sel = [a for a in pts if a["reading"] == rd and a["geometry"] == geo]
            if sel:
                ax.plot([a["length_over_lambda"] for a in sel], [a["predicted_over_lambda"] for a in sel], mk,
                        color=c, mfc=fill, label=f'"{rd}", {geo} ({len(sel)})')
            sel = [a for a in arrests if a["reading"] == rd and a["geometry"] == geo
                   and math.isfinite(a["G_over_Gamma_at_arrest"])]
            if sel:
                bx.plot([a["length_over_lambda"] for a in sel], [a["G_over_Gamma_at_arrest"] for a in sel], mk,
                        color=c, mfc=fill, label=f'"{rd}", {geo} ({len(sel)})')
    top = max([a["length_over_lambda"] for a in pts] + [a["predicted_over_lambda"] for a in pts] + [1.0])
    ax.plot([0, top], [0, top], "k-", lw=0.6)
    ax.set_xlabel("measured arrest length / Lambda")
    ax.set_ylabel("predicted (G falls to Gamma) / Lambda")
    ax.set_title(f"{len(pts)} of {len(arrests)} precursors reach G = Gamma", fontsize=8)
    bx.axhline(1.0, color="k", lw=0.6)
    bx.set_xlabel("measured arrest length / Lambda")
    bx.set_ylabel("static G / Gamma at the measured arrest")
    bx.set_title("LEFM arrest: G = Gamma (line)", fontsize=8)
    for a_ in (ax, bx):
        if a_.lines[:-1] or (a_ is bx and len(a_.lines) > 1):
            a_.legend(fontsize=7)
    return save(fig, img, "cracks_precursors_prediction", source)


def _fitted(rows: list[dict], arrests: list[dict], img: str, tables: str) -> tuple[str, dict]:
    """Each run's row gets the fit of its group (``fits``); the runs' table and the length figure written.
    Returns the Markdown of the runs' table and the figures' provenance."""
    fit = fits(arrests)
    nan = {"slope": math.nan, "intercept": math.nan, "r2": math.nan, "n_fit": 0}
    for r in rows:
        r.update(fit.get(group(r), nan))
    source = provenance(rows)
    length_figure(arrests, fit, img, source)
    return write(rows, RUN_COLS, os.path.join(tables, "cracks_precursors.csv")), source


def gather(dirs: list[str], read) -> tuple[list[dict], list[dict]]:
    """The runs' rows and their precursors' rows over the sweep folders ``dirs``: ``read(row, run)`` gives a run's
    row and its precursors (each study's ``run_arrests``); a point without a run is skipped."""
    rows, arrests = [], []
    for d in dirs:
        for row, run in points(d):
            if run is None:
                continue
            r, a = read({**row, "sweep": os.path.basename(d)}, run)
            rows.append(r)
            arrests += a
    return rows, arrests


def tabulate(runs: str, img: str, tables: str) -> str:
    """Both tables and both figures (module docstring); returns the Markdown of the runs' table."""
    rows, arrests = gather(sweeps(runs, "precursors"), run_arrests)
    table.write_csv(os.path.join(tables, "cracks_precursors_arrests.csv"), ARREST_COLS + ["scene", "commit"],
                    arrests)
    md, source = _fitted(rows, arrests, img, tables)
    prediction_figure(arrests, img, source)
    return md


def refit(tables: str, img: str) -> str:
    """The fits again from the tables ``tabulate`` wrote (``cracks_precursors.csv``, one row per run, and
    ``cracks_precursors_arrests.csv``, one per precursor), without the runs: the runs' table with its fit
    columns and the length figure rewritten, every other column and the rows' scene and commit as they were.
    Returns the Markdown of the runs' table."""
    rows = table.read_rows(os.path.join(tables, "cracks_precursors.csv"))
    arrests = table.read_rows(os.path.join(tables, "cracks_precursors_arrests.csv"))
    return _fitted(rows, arrests, img, tables)[0]
