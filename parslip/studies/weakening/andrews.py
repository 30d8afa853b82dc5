"""Study 1 of docs/studies/weakening.md: Andrews' transition distance against S on the slip-weakening interface.

Each point of ``run/studies/weakening_andrews*.toml`` holds a uniform prestress tau_0 and nucleates a bilateral
rupture at the contact's centre (``interface.nucleation``).  S, L_c, Lambda are the scene's (``parslip info``:
``rupture.law_scales``, the law at rest under F_N, tau_0 the held prestress); L_andrews = f(S) L_c with Xia et
al.'s f(S) = 9.8 (1.77 - S)^-3.  L_trans is measured on each side from the hypocentre (the zone's centre) by
``analysis.transition`` on the rupture-time field after the prestress was held: the daughter's birth, else the
first distance from which the tip runs above c_s to its end, either beyond where the rupture first broke a site
before its forced front reached it (``remeasure``: ``free``, at most the zone's half-width; the time-weakening
zone's edge); the table gives the mean of the two sides, and the reading beyond the zone's edge as ``L_zone``.  A
transition beyond the distance at which a wave reflected from the top or bottom reaches the tip
(2 h / sqrt(c_l^2 - c_r^2) for a tip at c_r) is not counted.  Lengths in a, speeds in c_r.
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis import lefm, transition
from parslip.analysis.fronts import wave_speeds
from parslip.analysis.rupture import law_scales
from parslip.model.physics import ROW_HEIGHT
from parslip.plot.figures import pyplot, save
from parslip.scene.derive import derive

from ..cracks.supershear import andrews_axes
from . import points, provenance, sweeps, write

COLS = ["sweep", "point", "S", "L_c", "L_trans", "L_andrews", "nucleation", "nucleation_over_Lc", "ratio",
        "trans_by", "resolution", "L_trans_plus", "L_trans_minus", "free", "L_zone", "v_exit", "reach", "room",
        "reflection", "uniform", "S_path", "Lambda", "tau_p", "tau_0", "Gamma", "kx", "softening", "heal_time",
        "zeta", "damping", "hold", "bottom_kn"]


def scales(run) -> dict:
    """The scene's law scales (``rupture.law_scales``: tau_p, tau_r, D_c, Gamma, Lambda, tau_0, S, L_c)."""
    return law_scales(derive(run.scene, omega=(float(run.attrs["omega_max"]), "bound")))


def geometry(run) -> dict:
    """The nucleation's centre and half-width (a), the room to the nearer strong edge (the first patch whose
    zone lies beyond the centre, on either side, a) and the distance at which a wave reflected from the top
    or the bottom reaches a tip running at c_r from the centre (a)."""
    l = float(run.scene["lattice.top_cols"])
    lo, hi = run.scene["interface.nucleation.x"]
    c = 0.5 * (lo + hi)
    ahead = [p["x"][0] - c for p in run.scene["interface.patch"] if p["x"][0] > c]
    behind = [c - p["x"][1] for p in run.scene["interface.patch"] if p["x"][1] < c]
    h = float(min(run.scene["lattice.top_rows"], run.scene["lattice.bottom_rows"])) * ROW_HEIGHT
    return {"centre": c * l, "half": 0.5 * (hi - lo) * l, "room": min(ahead + behind + [c, 1 - c]) * l,
            "reflection": 2.0 * h / math.sqrt(wave_speeds(run)["c_l"] ** 2 - 1.0), "l": l}


def nucleation_start(run) -> float:
    """When the nucleation started (l/c_r): the held prestress reached, settled, and the nucleation's delay
    passed (NaN when the prestress was never reached)."""
    sc = run.scene
    return float(run.attrs["prestress_time"]) + float(sc["drive.prestress.settle"]) \
        + float(sc["interface.nucleation.start"])


def path_prestress(run, g: dict, within: float, tol: float = 0.05) -> tuple[float, float]:
    """The prestress the rupture ran into, in the last frame before the nucleation started: the mean shear
    traction (rho c_r^2) over the sites within ``within`` (a) of the centre, and how far from the centre (a,
    the nearer side) the traction stays within ``tol`` of its mean over the central L_c-wide stretch (the free
    edges of the finite block unload the contact near them)."""
    start = nucleation_start(run)
    t = np.asarray(run.interface["t"], float)
    k = max(int(np.searchsorted(t, start)) - 1, 0)
    sxy = np.asarray(run.interface["sxy"])[k]
    r = np.arange(len(sxy)) + 0.5 - g["centre"]
    mid = float(sxy[np.abs(r) <= max(g["half"], 1.0)].mean())
    off = np.abs(sxy - mid) > tol * mid
    uniform = min(float(np.min(np.abs(r)[off & (r * d > 0)], initial=g["l"])) for d in (1, -1))
    return float(sxy[np.abs(r) <= within].mean()), uniform


def sides(run, g: dict, within: float = math.inf) -> list[dict]:
    """``transition.transition_distance`` of each side (+x, -x) of the rupture, with its (r, t) arrivals, those
    up to ``within`` (a) from the hypocentre (all by default)."""
    times = transition.rupture_times(run, float(run.attrs["prestress_time"]))
    c_s = wave_speeds(run)["c_s"]
    out = []
    for d in (1, -1):
        r, t = transition.side(times, g["centre"], d, g["l"])
        r, t = r[r <= within], t[r <= within]
        out.append({**transition.transition_distance(r, t, c_s, g["half"]), "r": r, "t": t, "direction": d})
    return out


def _counted(side: dict, g: dict) -> float:
    """A side's L_trans when it came before the reflected wave (and inside the room), else NaN."""
    L = side["L_trans"]
    return L if math.isfinite(L) and L <= min(g["reflection"], g["room"]) else math.nan


def measure(run, cut: bool = False) -> dict:
    """The run's scales, geometry, both sides and their mean L_trans (NaN when a side has none counted); with
    ``cut``, each side's arrivals only up to the reflected wave or the room (so that a break the strong edge
    or a reflection caused beyond them is not taken for a daughter that hides the tip's own transition)."""
    sc, g = scales(run), geometry(run)
    both = sides(run, g, min(g["reflection"], g["room"]) if cut else math.inf)
    Ls = [_counted(s, g) for s in both]
    L = float(np.mean(Ls)) if all(math.isfinite(v) for v in Ls) else math.nan
    bys = {s["by"] for s, v in zip(both, Ls) if math.isfinite(v)}
    L_andrews = float(lefm.andrews_f(sc["S"]) * sc["L_c"])
    tau, uniform = path_prestress(run, g, min(L_andrews, g["room"]))
    return {"scales": sc, "geometry": g, "sides": both, "L_trans": L, "L_sides": Ls, "L_andrews": L_andrews,
            "by": " / ".join(sorted(bys)) if math.isfinite(L) else None,
            "resolution": max(s["resolution"] for s in both) if math.isfinite(L) else math.nan,
            "S_path_tau": tau, "uniform": uniform}


def remeasure(m: dict, run) -> dict:
    """``measure``'s result with each side's L_trans read beyond where the rupture first ran ahead of the
    forced front (``transition.free_start``) rather than beyond the zone's edge, which keeps a zone widened
    past where the rupture already runs by itself from moving L_trans without changing the run.  The old
    reading is kept as "L_zone", the mean start as "free" (a).  The forcing reaches r at r /
    nucleation.speed after the nucleation's start; a time-weakening zone weakens all at once, so its
    start stays the zone's edge."""
    g, sc = m["geometry"], run.scene
    c_s = wave_speeds(run)["c_s"]
    l, v = g["l"], float(sc["interface.nucleation.speed"])
    times = transition.rupture_times(run, float(run.attrs["prestress_time"]))
    origin = (nucleation_start(run) - np.nanmin(times)) * l if np.isfinite(times).any() else 0.0   # a/c_r
    sides, Ls = [], []
    for side in m["sides"]:
        r, t = side["r"], side["t"]
        free = transition.free_start(r, t, origin + r / v, g["half"]) if v > 0 else g["half"]
        got = {**side, **transition.transition_distance(r, t, c_s, free), "free": free,
               "v_exit": side["v_exit"]}
        sides.append(got)
        Ls.append(_counted(got, g))
    L = float(np.mean(Ls)) if all(math.isfinite(x) for x in Ls) else math.nan
    bys = {s["by"] for s, x in zip(sides, Ls) if math.isfinite(x)}
    return {**m, "sides": sides, "L_sides": Ls, "L_trans": L, "L_zone": m["L_trans"],
            "by": " / ".join(sorted(bys)) if math.isfinite(L) else None,
            "resolution": max(s["resolution"] for s in sides) if math.isfinite(L) else math.nan,
            "free": float(np.mean([s["free"] for s in sides]))}


def _row(sweep: str, row: dict, run) -> dict:
    out = {"sweep": sweep, "point": row["point"], "scene": row["scene"], "commit": row["commit"]}
    if run is None:
        return {**out, **{c: math.nan for c in COLS if c not in out}}
    m = remeasure(measure(run), run)
    sc, g, sc_ = m["scales"], m["geometry"], run.scene
    tp, tr, tau = sc["tau_p"], sc["tau_r"], m["S_path_tau"]
    L_andrews = m["L_andrews"]
    return {**out, "S": sc["S"], "L_c": sc["L_c"], "L_trans": m["L_trans"], "L_andrews": L_andrews,
            "nucleation": sc_["interface.nucleation.kind"], "nucleation_over_Lc": g["half"] / sc["L_c"],
            "ratio": m["L_trans"] / L_andrews, "trans_by": m["by"], "resolution": m["resolution"],
            "L_trans_plus": m["L_sides"][0], "L_trans_minus": m["L_sides"][1], "free": m["free"],
            "L_zone": m["L_zone"], "v_exit": float(np.nanmean([s["v_exit"] for s in m["sides"]])),
            "reach": min(s["reach"] for s in m["sides"]), "room": g["room"], "reflection": g["reflection"],
            "uniform": m["uniform"],
            "S_path": (tp - tau) / (tau - tr), "Lambda": sc["Lambda"], "tau_p": tp, "tau_0": sc["tau_0"],
            "Gamma": sc["Gamma"], "kx": sc_["interface.kx"], "softening": sc_["interface.softening"],
            "heal_time": sc_["interface.heal_time"], "zeta": sc_["time.zeta"],
            "damping": sc_["time.damping"], "hold": sc_["drive.hold"], "bottom_kn": sc_["material.bottom_kn"],
            "_m": m, "_run": run}


def rows(runs: str) -> list[dict]:
    """A row per run of the study's sweeps under ``runs`` (``COLS``, scene, commit; ``_m`` the measure)."""
    return [_row(os.path.basename(d), row, run) for d in sweeps(runs, "andrews") for row, run in points(d)]


def bound(r: dict) -> float:
    """How far a front that did not turn supershear was seen to stay below c_s in the conditions Andrews
    assumes: to its reach, the room, the reflected wave or the end of the uniform prestress, whichever came
    first (a)."""
    return min(r["reach"], r["room"], r["reflection"], r["uniform"])


def transition_figure(rs, img, source):
    """L_trans / L_c against S beside Andrews' f(S) and its factor-1.5 band; open triangles: no transition
    before the bound (a lower bound); the nucleation zone's half-width as a dash; crosses: the zone-edge
    reading (``L_zone``) where it differs from L_trans."""
    fig, ax = andrews_axes(1.6)
    styles = {"weakening_andrews": ("tab:blue", "forced, main sweep"),
              "weakening_andrews_nucleation": ("tab:orange", "nucleation controls"),
              "weakening_andrews_lattice": ("tab:green", "lattice controls"),
              "weakening_andrews_healing": ("tab:red", "bonds that do not re-form")}
    for sweep, (c, label) in styles.items():
        mine = [r for r in rs if r["sweep"] == sweep and np.isfinite(r["S"])]
        for kind, mk in (("forced", "o"), ("time", "s")):
            hit = [r for r in mine if np.isfinite(r["L_trans"]) and r["nucleation"] == kind]
            if hit:
                ax.plot([r["S"] for r in hit], [r["L_trans"] / r["L_c"] for r in hit], mk, color=c,
                        mfc="none" if kind == "time" else c, label=f"{label}, {kind}")
        moved = [r for r in mine if np.isfinite(r["L_zone"]) and r["L_zone"] != r["L_trans"]]
        ax.plot([r["S"] for r in moved], [r["L_zone"] / r["L_c"] for r in moved], "x", color=c, ms=5)
        miss = [r for r in mine if not np.isfinite(r["L_trans"])]
        ax.plot([r["S"] for r in miss], [bound(r) / r["L_c"] for r in miss], "^", color=c, mfc="none")
        ax.plot([r["S"] for r in mine], [r["nucleation_over_Lc"] for r in mine], "_", color=c, ms=9)
    ax.set_yscale("log")
    ax.set_xlabel("S (the scene's: tau_p and tau_0 from parslip info)")
    ax.set_ylabel("L_trans / L_c")
    ax.legend(fontsize=6)
    ax.set_title("supershear transition, slip-weakening interface, matched pair\n"
                 "^: none before the reflected wave, the room or the uniform prestress's end (a lower bound)\n"
                 "-: the zone's half-width; squares: time-weakening nucleation; x: read beyond the zone's edge",
                 fontsize=7)
    return save(fig, img, "weakening_andrews_transition", source)


def tips_figure(rs, img, source):
    """Each main-sweep run's rupture-time field on its +x side: distance from the hypocentre against the
    rupture time, with slopes c_R, c_s and c_l, and each run's reflection distance."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    waves = None
    for r in rs:
        if "_m" not in r or r["sweep"] != "weakening_andrews":
            continue
        waves = waves or wave_speeds(r["_run"])
        s = r["_m"]["sides"][0]
        line, = ax.plot(s["t"], s["r"], lw=1, label=f"S = {r['S']:.1f}")
        ax.axhline(r["reflection"], color=line.get_color(), ls=":", lw=0.6)
    tips_axes(ax, waves, 600.0, (0, 600), (0, 700),
              "weakening_andrews: rupture fronts (dotted: where the reflected wave arrives)")
    return save(fig, img, "weakening_andrews_tips", source)


def tips_axes(ax, waves: dict, t_max: float, xlim, ylim, title: str) -> None:
    """The axes of a tip-position figure (distance from the hypocentre against time since the first break):
    the lines of the waves in ``waves`` (c_R, c_s, c_l in c_r) up to ``t_max``, the limits, labels, legend
    and title."""
    if waves:
        t = np.array([0.0, t_max])
        for key, ls in (("c_R", "-"), ("c_s", "--"), ("c_l", "-.")):
            ax.plot(t, waves[key] * t, ls, color="0.5", lw=0.8, label=f"{key} = {waves[key]:.3g} c_r")
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_xlabel("time since the first break (a / c_r)")
    ax.set_ylabel("distance from the hypocentre, +x side (a)")
    ax.legend(fontsize=6, ncol=2)
    ax.set_title(title, fontsize=8)


def tabulate(runs: str, img: str, tables: str) -> str:
    """weakening_andrews.csv (a row per run, ``COLS`` then scene and commit) and its two figures; returns the
    Markdown table."""
    rs = rows(runs)
    source = provenance(rs)
    md = write(rs, COLS, os.path.join(tables, "weakening_andrews.csv"))
    transition_figure(rs, img, source)
    tips_figure(rs, img, source)
    return md
