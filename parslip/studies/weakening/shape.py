"""Study 2 of docs/studies/weakening.md: the law's shape.  L_trans at one S and one Gamma against the law's
elastic share.

The bond's law (``model.interface``) rises elastically to its peak tau_p = k_x x_b at the stretch x_b, then
weakens linearly over D_c more to tau_r; its fracture energy is

    Gamma = tau_p x_b / 2 + (tau_p - tau_r) D_c / 2  =  (tau_p - tau_r) D_c,eff / 2      (m c_r^2 / a)

and its elastic share is the first term over Gamma, s = tau_p x_b / (2 Gamma) (x_b / (x_b + D_c) at tau_r =
0).  Andrews' law is s = 0 (rigid to the peak), the paper's bond s = 1 (D_c = 0).  The points of
``run/studies/weakening_shape*.toml`` keep tau_p, Gamma (so D_c,eff, L_c and Lambda) and the nucleation and
trade x_b (through k_x and delta_b) against D_c.  S, L_c, Lambda and L_trans are measured as in study 1
(``andrews.measure``), each side's arrivals up to the reflected wave or the strong edge, with one change:
L_trans is read beyond where the rupture first ran ahead of its forced front (``free_start``), which may lie
inside the zone, not beyond the zone's edge (study 1's reading, kept as ``L_zone``): a zone widened past where
the rupture already runs by itself would otherwise move L_trans without changing the run.  Beside them,
without a free parameter:

    L_nuc    = 1.158 M D_c / (tau_p - tau_r)          the weakening branch's nucleation length (a; Uenishi &
                                                      Rice 2003), which sets the daughter crack's (Dunham 2007)
    L_dunham = f(S) L_c D_c / D_c,eff = f(S) L_c (1 - s)   Andrews' distance at s = 0, scaled as L_nuc
                                                      (a: Dunham's L_trans proportional to the daughter's
                                                      nucleation length, at equal Gamma)

and the time (a/c_r since the first break) at which the longitudinal wave the nucleation sent to the top and
bottom faces (h away) returns to the interface at the transition, sqrt(L_trans^2 + (2 h)^2) / c_l, against
the time the transition took.  Lengths in a, speeds in c_r.
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis import lefm, transition
from parslip.analysis.fronts import wave_speeds
from parslip.io.contract import EVENT_BREAK
from parslip.model.physics import ROW_HEIGHT
from parslip.plot.figures import pyplot, save

from . import andrews, points, provenance, sweeps, write

# Uenishi & Rice (2003): a linear slip-weakening patch under a peaked load goes unstable at half-length
# 1.158 M / W, W = (tau_p - tau_r) / D_c the weakening rate (M = mu / (1 - nu) in mode II).
UENISHI_RICE = 1.158

COLS = ["sweep", "point", "S", "elastic_share", "Gamma", "L_trans", "L_c", "L_trans_over_Lc", "L_dunham",
        "L_nuc", "early_breaks", "trans_by", "resolution", "L_trans_plus", "L_trans_minus", "free", "L_zone",
        "v_exit", "t_trans", "t_reflect",
        "reflection", "room", "uniform", "nucleation_over_Lc", "S_path", "Lambda", "tau_p", "tau_0", "x_b", "D_c",
        "D_c_eff", "kx", "ky", "delta_b", "heal_time", "zeta", "damping", "hold", "bottom_kn"]


def effective_dc(sc: dict) -> float:
    """D_c,eff = 2 Gamma / (tau_p - tau_r) (a): the slip over which a law rigid to its peak takes the same
    Gamma at the same strength drop.  Written in the law's own lengths, x_b tau_p / (tau_p - tau_r) + D_c,
    from the law's scales (``rupture.law_scales``: x_b, D_c in a; tau_p, tau_r in one unit)."""
    tp, tr = sc["tau_p"], sc["tau_r"]
    return sc["x_b"] * tp / (tp - tr) + sc["D_c"]


def elastic_share(sc: dict) -> float:
    """The share of Gamma the bond stores elastically up to its peak, tau_p x_b / (2 Gamma) = x_b tau_p /
    ((tau_p - tau_r) D_c,eff): 0 for Andrews' law (rigid to the peak), 1 for a bond that breaks at its peak."""
    tp, tr = sc["tau_p"], sc["tau_r"]
    return sc["x_b"] * tp / ((tp - tr) * effective_dc(sc))


def nucleation_length(Lambda: float, d_c: float, d_c_eff: float) -> float:
    """Uenishi & Rice's (2003) nucleation half-length of the weakening branch, 1.158 M D_c / (tau_p - tau_r)
    (a), written through Palmer & Rice's Lambda = 9 pi/16 M Gamma / (tau_p - tau_r)^2 = 9 pi/32 M D_c,eff /
    (tau_p - tau_r) so that no stress unit enters: 1.158 (32 / (9 pi)) Lambda D_c / D_c,eff.  0 for a bond
    that breaks at its peak (D_c = 0)."""
    return UENISHI_RICE * 32.0 / (9.0 * math.pi) * Lambda * d_c / d_c_eff


def dunham_length(S: float, L_c: float, share: float) -> float:
    """Andrews' distance f(S) L_c for the law rigid to its peak (share 0), scaled as the weakening branch's
    nucleation length at equal Gamma and tau_p (D_c = (1 - share) D_c,eff): f(S) L_c (1 - share) (units of
    L_c).  Dunham (2007) finds L_trans proportional to the daughter crack's nucleation length; this is that
    proportionality with Andrews' constant, nothing fitted."""
    return float(lefm.andrews_f(S)) * L_c * (1.0 - share)


def reflection_time(L: float, h: float, c_l: float) -> float:
    """When (a/c_r after the first break at the hypocentre) the longitudinal wave it sent to a face h away
    (a) is back on the interface at distance L (a) from it: sqrt(L^2 + (2 h)^2) / c_l."""
    return math.hypot(L, 2.0 * h) / c_l


def _at(side: dict, L: float) -> float:
    """The rupture time (a/c_r) of the site of ``side`` at distance L (a), NaN when L is not one of its sites."""
    hit = np.flatnonzero(np.isclose(side["r"], L))
    return float(side["t"][hit[0]]) if len(hit) else math.nan


def _timing(m: dict, run) -> tuple[float, float]:
    """The transition's time (the later side's, a/c_r) and the reflected wave's return there (a/c_r)."""
    if not math.isfinite(m["L_trans"]):
        return math.nan, math.nan
    t = max(_at(s, L) for s, L in zip(m["sides"], m["L_sides"]))
    h = float(min(run.scene["lattice.top_rows"], run.scene["lattice.bottom_rows"])) * ROW_HEIGHT
    return t, reflection_time(max(m["L_sides"]), h, wave_speeds(run)["c_l"])


def early_breaks(run) -> int:
    """How many sites broke before the nucleation started (the held prestress reached, settled and the
    nucleation's delay passed); every site that broke when the prestress was never reached.  Such a run's
    rupture did not start from the nucleation: it has no L_trans."""
    start = andrews.nucleation_start(run)
    ev = run.interface["events"]
    brk = np.asarray(ev["kind"]) == EVENT_BREAK
    t = np.asarray(ev["time"], float)[brk]
    early = t < start if math.isfinite(start) else np.ones(len(t), bool)
    return int(len(np.unique(np.asarray(ev["site"])[brk][early])))


def _row(sweep: str, row: dict, run) -> dict:
    out = {"sweep": sweep, "point": row["point"], "scene": row["scene"], "commit": row["commit"]}
    if run is None:
        return {**out, **{c: math.nan for c in COLS if c not in out}}
    m = andrews.remeasure(andrews.measure(run, cut=True), run)
    early = early_breaks(run)
    if early:                                      # a rupture the nucleation did not start: no L_trans
        m = {**m, "L_trans": math.nan, "L_sides": [math.nan, math.nan], "L_zone": math.nan,
             "by": "broke before the nucleation"}
    sc, g, sc_ = m["scales"], m["geometry"], run.scene
    share = elastic_share(sc)
    t_trans, t_reflect = _timing(m, run)
    tp, tr, tau = sc["tau_p"], sc["tau_r"], m["S_path_tau"]
    return {**out, "S": sc["S"], "elastic_share": share, "Gamma": sc["Gamma"], "L_trans": m["L_trans"],
            "L_c": sc["L_c"], "L_trans_over_Lc": m["L_trans"] / sc["L_c"],
            "L_dunham": dunham_length(sc["S"], sc["L_c"], share),
            "L_nuc": nucleation_length(sc["Lambda"], sc["D_c"], effective_dc(sc)),
            "early_breaks": early, "trans_by": m["by"], "resolution": m["resolution"],
            "L_trans_plus": m["L_sides"][0], "L_trans_minus": m["L_sides"][1], "free": m["free"],
            "L_zone": m["L_zone"], "v_exit": float(np.nanmean([s["v_exit"] for s in m["sides"]])),
            "t_trans": t_trans, "t_reflect": t_reflect, "reflection": g["reflection"], "room": g["room"],
            "uniform": m["uniform"], "nucleation_over_Lc": g["half"] / sc["L_c"], "S_path": (tp - tau) / (tau - tr),
            "Lambda": sc["Lambda"], "tau_p": tp, "tau_0": sc["tau_0"], "x_b": sc["x_b"], "D_c": sc["D_c"],
            "D_c_eff": effective_dc(sc), "kx": sc_["interface.kx"], "ky": sc_["interface.ky"],
            "delta_b": sc_["interface.delta_b"], "heal_time": sc_["interface.heal_time"], "zeta": sc_["time.zeta"],
            "damping": sc_["time.damping"], "hold": sc_["drive.hold"], "bottom_kn": sc_["material.bottom_kn"],
            "_m": m, "_run": run}


def rows(runs: str) -> list[dict]:
    """A row per run of the study's sweeps under ``runs`` (``COLS``, scene, commit; ``_m`` the measure)."""
    return [_row(os.path.basename(d), row, run) for d in sweeps(runs, "shape") for row, run in points(d)]


# Each sweep's colour and label in the figures.
STYLES = {"weakening_shape": ("tab:red", "k_y = 0.3, zone 1.5 L_c"),
          "weakening_shape_normal": ("tab:blue", "k_y = 1.2, zone 1.5 L_c"),
          "weakening_shape_zone": ("tab:green", "zone 2.5 L_c")}


def share_figure(rs, img, source):
    """L_trans / L_c against the elastic share, beside Andrews' f(S) (share 0), the scaling of the daughter's
    nucleation length f(S) (1 - s) and L_nuc / L_c; open triangles: no transition before the bound; crosses: a
    run whose contact broke before the nucleation (no L_trans)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ok = [r for r in rs if "_m" in r]
    if ok:
        S = float(np.mean([r["S"] for r in ok]))
        s = np.linspace(0.0, 1.0, 101)
        f = float(lefm.andrews_f(S))
        ax.plot(s, f * (1 - s), "k-", lw=1, label=f"f(S) (1 - s): Andrews' f({S:.2f}) = {f:.3g} at s = 0, "
                "scaled as the daughter's nucleation length")
        r0 = ok[0]
        ax.plot(s, nucleation_length(r0["Lambda"], 1 - s, 1.0) / r0["L_c"], "k:", lw=1,
                label="L_nuc / L_c (Uenishi & Rice 2003)")
    for sweep, (c, label) in STYLES.items():
        mine = [r for r in ok if r["sweep"] == sweep]
        hit = [r for r in mine if math.isfinite(r["L_trans"])]
        miss = [r for r in mine if not math.isfinite(r["L_trans"]) and not r["early_breaks"]]
        early = [r for r in mine if r["early_breaks"]]
        ax.plot([r["elastic_share"] for r in hit], [r["L_trans_over_Lc"] for r in hit], "o", color=c,
                mfc="none" if sweep.endswith("normal") else c, label=f"lattice, {label}")
        ax.plot([r["elastic_share"] for r in miss], [andrews.bound(r) / r["L_c"] for r in miss], "^", color=c,
                mfc="none")
        ax.plot([r["elastic_share"] for r in early], [0.2] * len(early), "x", color=c,
                label=f"{label}: broke before the nucleation" if early else None)
    ax.plot([r["elastic_share"] for r in ok], [r["nucleation_over_Lc"] for r in ok], "_", color="0.3", ms=10,
            label="the forced zone's half-width")
    ax.set_xlim(-0.03, 1.03)
    ax.set_ylim(0, None)
    ax.set_xlabel("elastic share s = tau_p x_b / (2 Gamma)  (0: Andrews' law, 1: the paper's)")
    ax.set_ylabel("L_trans / L_c")
    ax.legend(fontsize=6)
    ax.set_title("supershear transition at one S and one Gamma against the law's shape", fontsize=8)
    return save(fig, img, "weakening_shape_transition", source)


def tips_figure(rs, img, source):
    """Each run's rupture-time field on its +x side (distance from the hypocentre against the rupture time),
    with slopes c_R, c_s and c_l, each run's L_trans marked."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    waves, reach = None, 0.0
    for r in rs:
        if "_m" not in r or r["early_breaks"]:
            continue
        waves = waves or wave_speeds(r["_run"])
        s = r["_m"]["sides"][0]
        line, = ax.plot(s["t"], s["r"], lw=1, ls={"weakening_shape": "-", "weakening_shape_normal": "--"}.get(
            r["sweep"], ":"), label=f"s = {r['elastic_share']:.3g}, k_y = {r['ky']:.2g}, zone "
            f"{r['nucleation_over_Lc']:.2g} L_c")
        if math.isfinite(r["L_trans_plus"]):
            ax.plot(_at(s, r["L_trans_plus"]), r["L_trans_plus"], "o", color=line.get_color(), ms=4)
        reach = max(reach, r["reflection"])
    andrews.tips_axes(ax, waves, reach, (0, reach / 1.1 if reach else None), (0, reach if reach else None),
                      "weakening_shape: rupture fronts by elastic share (dots: L_trans)")
    return save(fig, img, "weakening_shape_tips", source)


def tabulate(runs: str, img: str, tables: str) -> str:
    """weakening_shape.csv (a row per run, ``COLS`` then scene and commit) and its two figures; returns the
    Markdown table."""
    rs = rows(runs)
    source = provenance(rs)
    md = write(rs, COLS, os.path.join(tables, "weakening_shape.csv"))
    share_figure(rs, img, source)
    tips_figure(rs, img, source)
    return md
