"""Study 3 of docs/studies/weakening.md: the cohesive zone's contraction with front speed (Svetlizky & Fineberg,
Nature 2014), on the slip-weakening interface.

Each run of ``run/studies/weakening_cohesive_zone*.toml`` holds a prestress and nucleates a bilateral crack in
it; each tip leaves the forced nucleation and accelerates towards c_R.  Along each tip's path ``analysis.zone``
gives, at every break, the weakening zone's width X_c at that instant (``front_zone``) and the tip's local speed;
route 2 of ``analysis.cracks`` is fitted ahead of the zone at every frame (``zone_field``).  A row is one front at
one stretch of its path: the longest run of consecutive sites its own rupture broke (``free_sites``) whose local
speed lies within ``BIN`` c_R of a target speed (``TARGETS``), their mean speed and width, and the mean G of the
frames over that stretch, over Gamma: ``G_field_over_Gamma`` with xi counted from the zone's tail (the break, as
route 2 of ``analysis.cracks`` counts it), ``G_field_centre_over_Gamma`` and ``G_field_head_over_Gamma`` from its
centre and head (the fit does not fix the origin; the three show what it moves).  Beside them, the law's static
width and its contraction at the lattice's wave speeds (``analysis.lefm``):

    X_c0 = c M Gamma / (tau_p - tau_r)^2,  c = 1.4623 (``lefm.linear_slip_zone``, linear slip weakening),
    X_c_lefm(v) = X_c0 / A_II(v)            (Rice 1980; Freund 1990, Eqs. 6.2.32-35),

Gamma the law's whole fracture energy (the elastic share before the peak included: D_c,eff = 2 Gamma /
(tau_p - tau_r)); ``X_c0_weakening`` reads Gamma as the weakening's area alone ((tau_p - tau_r) D_c / 2), the
other end of what the elastic share can move.  Neither is fitted.

Each row also says whether a reflected wave had reached the tip: ``reflection_margin`` (a/c_r), the earliest
arrival at the row's sites of a P wave sent from anywhere on the run's fronts' paths (``reflection_times``: off a
block's far face or its lateral face), minus the site's break, the least over the row (negative: a reflection
had arrived); ``free_reflection_margin`` the same from the free rupture's sites alone (the forced nucleation
grows slowly and sends little), which ``clean`` reads; and how long the crack was (``half_length``, a, from the
hypocentre: small-scale yielding asks for many X_c).
"""
from __future__ import annotations

import glob
import math
import os

import numpy as np

from parslip.analysis import lefm, table
from parslip.analysis.fronts import wave_speeds
from parslip.analysis.rupture import law_scales
from parslip.analysis.zone import ORIGINS, block_solid, front_zone, zone_field
from parslip.plot.figures import pyplot, save
from parslip.studies.cracks import points, provenance, write

NAME = "weakening_cohesive_zone"
# The speeds (over c_R) a row is read at, and the half-width of the band of local speeds a row averages.
TARGETS = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
BIN = 0.05
# A row needs this many sites (each a width at one instant).
MIN_SITES = 3
# Route 2's window ahead of the zone's head, in Lambda (Palmer & Rice's zone of the law, ``law_scales``).
WINDOW = (1.0, 3.0)
# How many sites' worth of the forced front's time a site may break ahead of its schedule and still count as
# forced (the forced front runs a site or two ahead of the schedule read from its first break).
FORCED_SLACK = 5.0
# Sites closer than this (in Lambda) to the held stretch's ends (the strong edges) are left out.
EDGE = 3.0
# The agreement the issue asks for (X_c(v)/X_c0 against the prediction, G against Gamma).
AGREE = 0.15
COLS = ["run", "front", "direction", "S", "tau_0", "L_c", "Lambda", "v", "n_sites", "X_c", "X_c_sd", "X_c0",
        "X_c0_weakening", "X_c_lefm", "X_c_over_lefm", "tau_p_reached", "X_c0_local", "X_c_over_lefm_local",
        "half_length", "G_field_over_Gamma",
        "G_field_centre_over_Gamma", "G_field_head_over_Gamma", "frames",
        "reflection_margin", "free_reflection_margin", "clean",
        "damping", "zeta", "bottom_kn", "contact", "D_c", "interface_dt"]
SHOWN = ["run", "front", "S", "v", "n_sites", "X_c", "X_c0", "X_c_lefm", "X_c_over_lefm", "tau_p_reached",
         "X_c_over_lefm_local", "half_length",
         "G_field_over_Gamma", "G_field_centre_over_Gamma", "G_field_head_over_Gamma", "reflection_margin",
         "free_reflection_margin"]


def law(run) -> dict:
    """The law's scales on the run (``rupture.law_scales`` of its scene) with the prestress it held
    (``prestress_tau``, read on the run): tau_p, tau_r, tau_0 (rho c_r^2), Gamma, Lambda, D_c, x_b, S, L_c,
    X_c0 and X_c0_weakening (a)."""
    from parslip.scene.derive import derive
    k = law_scales(derive(run.scene))
    drop = k["tau_p"] - k["tau_r"]
    tau0 = float(run.attrs.get("prestress_tau", k["tau_0"]))
    x0 = lefm.linear_slip_zone() / lefm.PALMER_RICE * k["Lambda"]        # c M Gamma / drop^2, in a
    weak = drop * k["D_c"] / (k["tau_p"] * k["x_b"] + drop * k["D_c"])     # the weakening's share of Gamma
    out = {**k, "tau_0": tau0, "S": (k["tau_p"] - tau0) / (tau0 - k["tau_r"]),
           "L_c": 2.0 / math.pi / lefm.PALMER_RICE * k["Lambda"] * (drop / (tau0 - k["tau_r"])) ** 2,
           "X_c0": x0, "X_c0_weakening": x0 * weak}
    return {name: float(value) for name, value in out.items()}


def reflection_times(run, sources: list, x) -> np.ndarray:
    """The earliest time (l/c_r) a P wave sent from any arrival (t, x) of ``sources`` (fronts) reaches the
    interface at x (l) after a reflection off a block's far face (the shorter block's height h: a path
    sqrt(dx^2 + (2 h)^2)) or off the lateral face ahead (x = 0 or 1: a path |x_f - x_s| + |x_f - x|)."""
    s = run.scene
    l, c_l = float(run.attrs["l"]), wave_speeds(run)["c_l"]
    h = min(s["lattice.top_rows"], s["lattice.bottom_rows"]) * math.sqrt(3.0) / 2.0
    ts = np.concatenate([np.asarray(f.tip["t"], float) for f in sources])
    xs = np.concatenate([np.asarray(f.tip["x"], float) for f in sources])
    x = np.atleast_1d(np.asarray(x, float))[:, None]
    far = ts + np.sqrt(((x - xs) * l) ** 2 + (2 * h) ** 2) / c_l / l
    side = ts + np.minimum(x + xs, 2.0 - x - xs) * l / c_l / l
    return np.minimum(far.min(axis=1), side.min(axis=1))


def free_sites(run, front, lam: float) -> np.ndarray:
    """Which sites of the front's path its own rupture broke, free of the set-up: not by the forced nucleation
    (a site inside the nucleation zone that broke no earlier than the forced front's schedule, the front's first
    break plus the distance from the zone's centre over ``interface.nucleation.speed``, less the time the
    forced front takes over ``FORCED_SLACK`` sites: the schedule's start is a break, not the nucleation's
    start), not within
    ``EDGE`` Lambda of the held stretch's ends (``drive.prestress.x``: the strong edges ahead), and not after
    the tip's fastest site (the front then meets the edge's patch and slows)."""
    s, l = run.scene, float(run.attrs["l"])
    x, t = np.asarray(front.tip["x"], float), np.asarray(front.tip["t"], float)
    lo, hi = s["interface.nucleation.x"] or [0.5, 0.5]
    centre, v_f = 0.5 * (lo + hi), s["interface.nucleation.speed"] or math.inf
    schedule = front.nucleation_time + np.abs(x - centre) / v_f
    forced = (x >= lo) & (x < hi) & (t >= schedule - FORCED_SLACK / (v_f * l))
    a, b = s["drive.prestress.x"]
    inside = (x >= a + EDGE * lam / l) & (x <= b - EDGE * lam / l)
    v = np.abs(np.asarray(front.tip.get("v", np.zeros(len(x))), float))
    before = np.arange(len(x)) <= (int(np.nanargmax(v)) if np.isfinite(v).any() else len(x))
    return ~forced & inside & before


def front_rows(run, k: int, front, fronts: list, scales: dict) -> list[dict]:
    """The rows of one front (``TARGETS``; see the module docstring)."""
    zone = front_zone(run, front)
    c_R, c_s, l = wave_speeds(run)["c_R"], wave_speeds(run)["c_s"], float(run.attrs["l"])
    lam = scales["Lambda"]
    fields = {o: zone_field(run, front, zone, (WINDOW[0] * lam, WINDOW[1] * lam), o) for o in ORIGINS}
    solid = block_solid(run)
    v = zone["v"] / c_R
    free = free_sites(run, front, lam)
    sources = [_Path(f, free_sites(run, f, lam)) for f in fronts]
    rows = []
    for target in TARGETS:
        sel = longest_run(np.flatnonzero((np.abs(v - target) <= BIN) & np.isfinite(zone["X_c"]) & free))
        if len(sel) < MIN_SITES:
            continue
        t0, t1 = zone["t_break"][sel].min(), zone["t_break"][sel].max()
        g = {o: _mean_in(f["t"], f["G"], t0, t1) / scales["Gamma"] for o, f in fields.items()}
        vv = float(np.mean(zone["v"][sel]))
        lefm_x = scales["X_c0"] * float(lefm.zone_contraction(vv / c_s, solid))
        xc = float(np.mean(zone["X_c"][sel]))
        local = local_zone(scales, float(np.mean(zone["tau_reached"][sel])))
        margin = float(np.min(reflection_times(run, fronts, zone["x"][sel]) - zone["t_break"][sel])) * l
        free_margin = float(np.min(reflection_times(run, sources, zone["x"][sel]) - zone["t_break"][sel])) * l
        rows.append({"front": k, "direction": front.direction, "v": vv / c_R, "n_sites": len(sel), "X_c": xc,
                     "X_c_sd": float(np.std(zone["X_c"][sel])), "X_c_lefm": lefm_x, "X_c_over_lefm": xc / lefm_x,
                     "tau_p_reached": local["ratio"], "X_c0_local": local["X_c0"],
                     "X_c_over_lefm_local": xc / (lefm_x * local["X_c0"] / scales["X_c0"]),
                     "half_length": float(np.mean(np.abs(zone["x"][sel] - front.nucleation_x))) * l,
                     "G_field_over_Gamma": g["tail"], "G_field_centre_over_Gamma": g["centre"],
                     "G_field_head_over_Gamma": g["head"],
                     "frames": int(np.count_nonzero((fields["centre"]["t"] >= t0) & (fields["centre"]["t"] <= t1))),
                     "reflection_margin": margin, "free_reflection_margin": free_margin,
                     "clean": free_margin > 0})
    return rows


class _Path:
    """The arrivals of a front at its free sites (``free_sites``), as ``reflection_times`` reads a source."""

    def __init__(self, front, keep):
        self.tip = {"t": np.asarray(front.tip["t"], float)[keep], "x": np.asarray(front.tip["x"], float)[keep]}


def local_zone(scales: dict, tau_reached: float) -> dict:
    """X_c0 of the law with the peak the sites reached: the held shear's moment loads the contact in
    compression at one end and in tension at the other (``/interface/syy`` varies linearly along it), so the
    gap y, the peak slip x_b = sqrt(delta_b^2 - y^2) and tau_p = k_x x_b / a differ from the scene's values at
    rest under F_N.  With r = tau_reached / tau_p the ratio the sites reached (x_b scales with it), Gamma =
    tau_p (x_b + D_c) / 2 (tau_r = 0) and X_c0 = c M Gamma / tau_p^2 scale as (r x_b + D_c) / ((x_b + D_c) r).
    {"ratio": r, "X_c0": that X_c0 (a)}; NaN with a residual (the scaling holds at tau_r = 0 only)."""
    r = tau_reached / scales["tau_p"]
    if scales["tau_r"] != 0 or not math.isfinite(r) or r <= 0:
        return {"ratio": r, "X_c0": math.nan}
    xb, dc = scales["x_b"], scales["D_c"]
    return {"ratio": r, "X_c0": scales["X_c0"] * (r * xb + dc) / ((xb + dc) * r)}


def longest_run(idx) -> np.ndarray:
    """The longest stretch of consecutive indices in the sorted ``idx``: the sites a front crossed in one go
    while its speed stayed in a band (the first such stretch of the longest length)."""
    idx = np.asarray(idx, int)
    if not len(idx):
        return idx
    cuts = np.flatnonzero(np.diff(idx) != 1) + 1
    runs = np.split(idx, cuts)
    return runs[int(np.argmax([len(r) for r in runs]))]


def _mean_in(t, values, t0: float, t1: float) -> float:
    a = np.asarray(values, float)[(np.asarray(t) >= t0) & (np.asarray(t) <= t1)]
    a = a[np.isfinite(a)]
    return float(a.mean()) if len(a) else math.nan


def run_rows(row: dict, run) -> list[dict]:
    """Every row of one run: its fronts that moved, each read at ``TARGETS``."""
    scales = law(run)
    s = run.scene
    fronts = [f for f in run.fronts() if f.direction != 0 and len(f.tip["t"]) >= 3]
    out = []
    for k, f in enumerate(fronts):
        for r in front_rows(run, k, f, fronts, scales):
            out.append({"run": f"{row['sweep']}/{row['point']}", **r, "S": scales["S"], "tau_0": scales["tau_0"],
                        "L_c": scales["L_c"], "Lambda": scales["Lambda"], "X_c0": scales["X_c0"],
                        "X_c0_weakening": scales["X_c0_weakening"], "damping": s["time.damping"],
                        "zeta": s["time.zeta"], "bottom_kn": s["material.bottom_kn"],
                        "contact": s["interface.contact"], "D_c": scales["D_c"],
                        "interface_dt": s["output.interface_dt"], "scene": row["scene"], "commit": row["commit"],
                        "solid": block_solid(run), "c_R_over_c_s": wave_speeds(run)["c_R"] /
                        wave_speeds(run)["c_s"]})
    return out


def rows_of(runs: str) -> list[dict]:
    """The rows of every run of the study's sweeps under ``runs`` (directories named as the sweep files)."""
    rows = []
    for d in sorted(glob.glob(os.path.join(runs, f"{NAME}*"))):
        for row, run in points(d):
            if run is not None:
                rows.extend(run_rows({**row, "sweep": os.path.basename(d)}, run))
    return rows


def zone_figure(rows: list[dict], img: str, source) -> list[str]:
    """X_c / X_c0 against v / c_R: the lattice's fronts (filled before any reflection reached them, open after),
    the prediction 1/A_II(v) at the lattice's wave speeds, and the same with Gamma read as the weakening's area
    alone (X_c0_weakening / X_c0 times it)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    if rows:
        r0 = rows[0]
        vv = np.linspace(0.0, 0.98, 200)
        pred = lefm.zone_contraction(vv * r0["c_R_over_c_s"], r0["solid"])
        ax.plot(vv, pred, "-", color="0.2", lw=1, label="1 / A_II(v) (Rice 1980), X_c0 of the whole Gamma")
        weak = r0["X_c0_weakening"] / r0["X_c0"]
        ax.plot(vv, weak * pred, "--", color="0.5", lw=1, label="the same, Gamma = (tau_p - tau_r) D_c / 2")
    colours = pyplot().get_cmap("tab10")
    for j, name in enumerate(sorted({(r["run"], r["front"]) for r in rows})):
        rr = [r for r in rows if (r["run"], r["front"]) == name]
        c = colours(j % 10)
        for clean in (True, False):
            sel = [r for r in rr if r["clean"] == clean]
            ax.errorbar([r["v"] for r in sel], [r["X_c"] / r["X_c0"] for r in sel],
                        yerr=[r["X_c_sd"] / r["X_c0"] for r in sel], fmt="o", color=c,
                        mfc=c if clean else "none", ms=6,
                        label=f"{name[0]} front {name[1]} (S = {rr[0]['S']:.2f})" if clean else None)
        ax.plot([r["v"] for r in rr], [r["X_c"] / r["X_c0_local"] for r in rr], "*", color=c, ms=7)
    ax.set_xlim(0, 1.0)
    ax.set_ylim(0, 1.4)
    ax.set_xlabel("front speed / c_R (the lattice's Rayleigh speed)")
    ax.set_ylabel("X_c / X_c0")
    ax.legend(fontsize=6, loc="lower left", title="open: a reflected wave had reached the tip; *: over X_c0_local "
              "(the peak the sites reached)", title_fontsize=6)
    ax.set_title("the weakening zone's width behind sub-Rayleigh tips", fontsize=8)
    return save(fig, img, f"{NAME}_width", source)


def energy_figure(rows: list[dict], img: str, source) -> list[str]:
    """G / Gamma by route 2 against v / c_R, the field's origin at the zone's tail (the break, as route 2 of
    ``analysis.cracks`` counts it: the dots), its centre (the ticks) and its head (the bars' other end)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for r in rows:
        lo, hi = sorted((r["G_field_over_Gamma"], r["G_field_head_over_Gamma"]))
        c = "C0" if r["clean"] else "C3"
        ax.plot([r["v"], r["v"]], [lo, hi], "-", color=c, lw=0.8)
        ax.plot(r["v"], r["G_field_centre_over_Gamma"], "_", color=c, ms=8)
        ax.plot(r["v"], r["G_field_over_Gamma"], "o", color=c, mfc=c if r["clean"] else "none", ms=5)
    ax.axhspan(1 - AGREE, 1 + AGREE, color="0.92")
    ax.axhline(1.0, color="0.3", lw=0.8, ls="--")
    ax.set_xlim(0, 1.0)
    ax.set_xlabel("front speed / c_R")
    ax.set_ylabel("G (route 2) / Gamma")
    ax.set_title("route 2 ahead of the zone, xi from its tail (dots), centre (ticks), head (bars' ends); "
                 "red: after a reflection", fontsize=7)
    return save(fig, img, f"{NAME}_g", source)


def summary(rows: list[dict]) -> str:
    """How many clean rows from 0.2 to 0.9 c_R meet the targets."""
    clean = [r for r in rows if r["clean"] and 0.15 <= r["v"] <= 0.95]
    ok_x = [r for r in clean if abs(r["X_c_over_lefm"] - 1) <= AGREE]
    ok_x_w = [r for r in clean if abs(r["X_c"] / (r["X_c_lefm"] * r["X_c0_weakening"] / r["X_c0"]) - 1) <= AGREE]
    ok_l = [r for r in clean if abs(r["X_c_over_lefm_local"] - 1) <= AGREE]
    ok_g = {o: sum(abs(r[c] - 1) <= AGREE for r in clean) for o, c in
            (("tail", "G_field_over_Gamma"), ("centre", "G_field_centre_over_Gamma"), ("head", "G_field_head_over_Gamma"))}
    return (f"{len(rows)} rows, {len(clean)} before any reflection of the free rupture's waves at 0.15-0.95 c_R; "
            f"X_c within {AGREE:.0%} of X_c0/A_II: {len(ok_x)} (of X_c0_weakening/A_II: {len(ok_x_w)}, of "
            f"X_c0_local/A_II: {len(ok_l)}); route 2 "
            f"within {AGREE:.0%} of Gamma, xi from the zone's tail, centre, head: {ok_g['tail']}, {ok_g['centre']}, "
            f"{ok_g['head']}.")


def tabulate(runs: str, img: str, tables: str) -> str:
    """weakening_cohesive_zone.csv, the two figures, and the Markdown the page quotes."""
    rows = rows_of(runs)
    os.makedirs(img, exist_ok=True)
    source = provenance(rows)
    write(rows, COLS, os.path.join(tables, f"{NAME}.csv"))
    zone_figure(rows, img, source)
    energy_figure(rows, img, source)
    for f in glob.glob(os.path.join(img, f"{NAME}_*.pdf")):
        os.remove(f)
    return table.markdown(rows, SHOWN) + "\n\n" + summary(rows)
