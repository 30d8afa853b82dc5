"""Study 1 of docs/studies/cracks.md: the fracture energy G of T0 fronts against their speed, by both routes of
``analysis.cracks``, over Gamma, the energy their breaks take.

A row per front that has a steady stretch (``cracks.measurable``) in every run of the sweeps
``run/studies/cracks_energy*.toml``: its speed v over the stretch (c_r, and over the lattice's c_R), its band,
route 1's G at the two contours (``G_contour_inner``, ``G_contour_outer``), route 2's (``G_field``), Gamma
(m c_r^2 / a), the longest pause of its tip over the stretch (``longest_pause``: whether it ran or stopped and
started again), what the interface takes inside each contour by the events (``cracks.interface_take``: net of
the re-formations, ``take_*``, and the breaks alone, ``breaks_*``), G/Gamma by route 1 (the inner contour), the
routes' ratio (route 1 over route 2), the contours' ratio, and what decides whether route 2 can be read: each
block's height in process zones (``height_lambda``; ``cracks.field_resolved`` asks for ``cracks.FIELD_HEIGHT``).
Route 2 is computed on every front (``cracks.front_energy``) so that the runs on blocks too short for it show
by how much it falls short; ``field_resolved`` says which rows the routes' comparison may use.
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis import cracks as gmeasures, table
from parslip.analysis.fronts import wave_speeds
from parslip.plot.figures import pyplot, save
from parslip.studies.cracks import points, provenance, sweeps, write

COLS = ["sweep", "point", "run", "front", "first", "t_nuc", "x_nuc", "damping", "zeta", "kx", "FN", "v0", "top_rows",
        "bottom_kn", "bottom_kt", "height_lambda", "Lambda", "v", "v_over_cR", "band", "G_contour_inner",
        "G_contour_outer", "G_field", "Gamma", "take_inner", "take_outer", "breaks_inner", "breaks_outer",
        "G_over_Gamma", "G_field_over_Gamma", "G_routes_ratio", "contours_ratio", "route1_ok", "field_resolved",
        "longest_pause", "snapshots", "frames"]
# What the page's table shows (the CSV holds every column).
SHOWN = ["sweep", "point", "front", "damping", "zeta", "kx", "height_lambda", "v_over_cR", "Gamma", "G_over_Gamma",
         "G_field_over_Gamma", "G_routes_ratio", "contours_ratio", "longest_pause"]
# The routes agree within this share (issue 27's target); route 1 is read where its two contours agree within
# CONTOURS (issue 26's target: what the interface dissipates between them is small); fronts slower than
# SLOWEST c_R are below the study's range.
AGREE = 0.15
CONTOURS = 0.10
SLOWEST = 0.1
# A front whose tip pauses over more than this share of its stretch (``longest_pause``) stops and starts again:
# its stretch has no speed, and the figures and the summary leave it out.
STOP_GO = 0.1


def ran(r: dict) -> bool:
    """Whether a row's front ran over its stretch (no pause longer than ``STOP_GO`` of it)."""
    return bool(r["longest_pause"] <= STOP_GO)


def height_lambda(run) -> float:
    """The shorter elastic block's height (rows times sqrt(3)/2 a) in process zones Lambda (``process_zone``)."""
    s = run.scene
    rows = min(s["lattice.top_rows"], s["lattice.bottom_rows"])
    return rows * math.sqrt(3.0) / 2.0 / gmeasures.process_zone(run)


def longest_pause(front) -> float:
    """The longest time between two successive arrivals of the tip over the front's steady stretch, as a share
    of the stretch's duration: a few hundredths for a front that runs, most of it for one that stops and
    starts again (its stretch's fitted speed is then no speed the tip ever had)."""
    st = gmeasures.steady_stretch(front)
    tt = np.asarray(front.tip["t"], float)[st["lo"]:st["hi"]]
    span = st["t1"] - st["t0"]
    return float(np.max(np.diff(tt)) / span) if len(tt) > 1 and span > 0 else math.nan


def _ratio(a: float, b: float) -> float:
    return a / b if math.isfinite(a) and math.isfinite(b) and b != 0 else math.nan


def front_row(sweep: str, row: dict, run, k: int, front) -> dict:
    """The table's row of front k of one run (``COLS``)."""
    e = gmeasures.front_energy(run, front)
    s, c_R = run.scene, wave_speeds(run)["c_R"]
    inner_outer = _ratio(e["G_contour_inner"], e["G_contour_outer"])
    return {"sweep": sweep, "point": row["point"], "run": os.path.basename(run.path), "front": k, "first": k == 0,
            "t_nuc": front.nucleation_time, "x_nuc": front.nucleation_x, "damping": s["time.damping"],
            "zeta": s["time.zeta"], "kx": s["interface.kx"], "FN": s["load.FN"],
            "v0": s["drive.v0"], "top_rows": s["lattice.top_rows"],
            "bottom_kn": s["material.bottom_kn"], "bottom_kt": s["material.bottom_kt"],
            "height_lambda": height_lambda(run), "Lambda": e["Lambda"], "v": e["v"], "v_over_cR": e["v"] / c_R,
            "band": front.band or "-", "G_contour_inner": e["G_contour_inner"],
            "G_contour_outer": e["G_contour_outer"], "G_field": e["G_field"], "Gamma": e["Gamma"],
            "take_inner": e["take_inner"], "take_outer": e["take_outer"],
            "breaks_inner": e["breaks_inner"], "breaks_outer": e["breaks_outer"],
            "G_over_Gamma": _ratio(e["G_contour_inner"], e["Gamma"]),
            "G_field_over_Gamma": _ratio(e["G_field"], e["Gamma"]),
            "G_routes_ratio": _ratio(e["G_contour_inner"], e["G_field"]),
            "contours_ratio": inner_outer, "route1_ok": bool(abs(inner_outer - 1) <= CONTOURS),
            "field_resolved": gmeasures.field_resolved(run), "longest_pause": longest_pause(front),
            "snapshots": e["snapshots"], "frames": e["frames"],
            "scene": row["scene"], "commit": row["commit"]}


def rows_of(runs: str) -> list[dict]:
    """Every measurable front of every run of the study's sweeps, a row each (``front_row``)."""
    rows = []
    for d in sweeps(runs, "energy"):
        for row, run in points(d):
            if run is None:
                continue
            for k, front in enumerate(run.fronts()):
                if gmeasures.measurable(run, front):
                    rows.append(front_row(os.path.basename(d), row, run, k, front))
    return rows


def _label(r: dict) -> str:
    # F_N and v0 only where a sweep moves them off the scene's 1 and 1e-3 (they set the front's speed there)
    load = (f", F_N {r['FN']:g}" if r["FN"] != 1.0 else "") + (f", v0 {r['v0']:g}" if r["v0"] != 1e-3 else "")
    return f"{r['damping']} {r['zeta']:g}, k_x {r['kx']:g}, {r['height_lambda']:.3g} Lambda{load}"


def _colours(rows: list[dict]) -> dict:
    """A colour per run setting (``_label``), from a 20-colour map."""
    names = sorted({_label(r) for r in rows}, key=lambda n: (n.split(",")[1], n))
    return {n: pyplot().get_cmap("tab20")(k % 20) for k, n in enumerate(names)}


def energy_figure(rows: list[dict], img: str, source) -> list[str]:
    """G/Gamma against v/c_R.  Each run's first front (the T0 front from the loaded edge, into the interface
    as the drive left it): route 1 filled where its two contours agree (``route1_ok``), route 2 open where
    the blocks resolve its field; later fronts (into what earlier ones left) small, route 1 only where its
    contours agree.  The line G = Gamma of Svetlizky & Fineberg (2014)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for name, c in _colours(rows).items():
        first = [r for r in rows if _label(r) == name and r["first"] and ran(r)]
        ok = [r for r in first if r["route1_ok"]]
        ax.plot([r["v_over_cR"] for r in ok], [r["G_over_Gamma"] for r in ok], "o", color=c, ms=7,
                label=f"{name}")
        res = [r for r in first if r["field_resolved"]]
        ax.plot([r["v_over_cR"] for r in res], [r["G_field_over_Gamma"] for r in res], "s", mfc="none", color=c, ms=7)
        later = [r for r in rows if _label(r) == name and not r["first"] and r["route1_ok"] and ran(r)]
        ax.plot([r["v_over_cR"] for r in later], [r["G_over_Gamma"] for r in later], ".", color=c, ms=4)
    ax.axhline(1.0, color="0.3", lw=0.8, ls="--")
    ax.text(0.12, 1.03, "G = Gamma (Svetlizky & Fineberg 2014)", fontsize=7, transform=ax.get_yaxis_transform())
    ax.axvspan(0, SLOWEST, color="0.92")
    ax.set_xlim(0, 1.05)
    ax.set_ylim(0, 2.0)
    ax.set_xlabel("front speed over its steady stretch / c_R (the lattice's Rayleigh speed)")
    ax.set_ylabel("G / Gamma")
    ax.legend(fontsize=6, ncol=2, loc="upper left", title="first fronts: o route 1, [] route 2 (resolved);"
              f" . later fronts, route 1; fronts that pause over {STOP_GO:.0%} of their stretch left out",
              title_fontsize=6)
    ax.set_title("T0 fronts between identical solids, l = 500 a: G / Gamma by both routes", fontsize=8)
    return save(fig, img, "cracks_energy_g_v", source)


# The marker of each block height (in Lambda, rounded): the route-2 figure tells the heights apart by it.
HEIGHT_MARKERS = ((7.0, "v"), (15.0, "D"), (30.0, "o"), (math.inf, "s"))


def gap_figure(rows: list[dict], img: str, source) -> list[str]:
    """Route 2 over route 1 (the inner contour) against v/c_R for each run's first front, the marker by the
    blocks' height in Lambda, filled where route 1's contours agree (``route1_ok``), open where they do not:
    whether route 2's shortfall follows the height (``cracks.FIELD_HEIGHT``), the speed or the damping."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9, 4.5))
    colours = _colours(rows)
    for r in rows:
        if not (r["first"] and ran(r) and math.isfinite(r["G_routes_ratio"]) and r["G_routes_ratio"] > 0):
            continue
        m = next(mk for h, mk in HEIGHT_MARKERS if r["height_lambda"] < h)
        c = colours[_label(r)]
        ax.plot(r["v_over_cR"], 1.0 / r["G_routes_ratio"], m, color=c, mfc=c if r["route1_ok"] else "none", ms=8,
                label=_label(r))
    ax.axhspan(1 - AGREE, 1 + AGREE, color="0.9")
    ax.axhline(1.0, color="0.3", lw=0.8, ls="--")
    ax.set_xlim(0, 1.05)
    ax.set_xlabel("front speed / c_R")
    ax.set_ylabel("route 2 / route 1 (inner contour)")
    ax.legend(fontsize=6, title="first fronts (marker: block height;\nopen: contours differ by > "
              f"{CONTOURS:.0%})", title_fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    ax.set_title(f"the field fit against the contour flux (band: within {AGREE:.0%})", fontsize=8)
    return save(fig, img, "cracks_energy_routes", source)


def summary(rows: list[dict]) -> str:
    """The study's numbers in one paragraph: first fronts, speeds, G/Gamma by route 1, the routes' agreement."""
    g = [r for r in rows if r["first"] and r["route1_ok"] and r["v_over_cR"] >= SLOWEST and ran(r)]
    both = [r for r in g if r["field_resolved"] and math.isfinite(r["G_routes_ratio"])]
    agree = [r for r in both if abs(r["G_routes_ratio"] - 1) <= AGREE]
    later = [r for r in rows if not r["first"] and r["route1_ok"] and r["field_resolved"] and ran(r)
             and math.isfinite(r["G_routes_ratio"])]
    stop_go = [r for r in rows if r["first"] and not ran(r)]
    if not g:
        return f"No first front with route 1's contours within {CONTOURS:.0%} of each other."
    v = np.array([r["v_over_cR"] for r in g])
    q = np.array([r["G_over_Gamma"] for r in g])
    return (f"{len(rows)} fronts in {len({(r['sweep'], r['point']) for r in rows})} runs.  First fronts with route "
            f"1's contours within {CONTOURS:.0%}: {len(g)}, at {v.min():.3g}-{v.max():.3g} c_R, G/Gamma "
            f"{q.min():.3g}-{q.max():.3g}; {len(both)} of them on blocks >= {gmeasures.FIELD_HEIGHT:g} Lambda "
            f"(route 2 resolved), {len(agree)} with the routes within {AGREE:.0%}.  Later fronts with both: "
            f"{len(later)}, {sum(abs(r['G_routes_ratio'] - 1) <= AGREE for r in later)} within {AGREE:.0%}.  "
            f"First fronts that stop and start again (a pause over {STOP_GO:.0%} of the stretch), left out: "
            f"{len(stop_go)}.")


def tabulate(runs: str, img: str, tables: str) -> str:
    """cracks_energy.csv (every measurable front), the two figures, and the Markdown the page quotes (the
    first fronts' rows and ``summary``)."""
    rows = rows_of(runs)
    source = provenance(rows)
    write(rows, COLS, os.path.join(tables, "cracks_energy.csv"))
    shown = table.markdown([r for r in rows if r["first"]], SHOWN)           # the page lists the first fronts
    energy_figure(rows, img, source)
    gap_figure(rows, img, source)
    return shown + "\n\n" + summary(rows)
