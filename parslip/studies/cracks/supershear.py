"""Study 3 of docs/studies/cracks.md: the supershear transition against Andrews' S.

Each point of ``run/studies/cracks_supershear.toml`` nucleates a crack at a weak patch (the last entry of
``interface.patch``) in a uniformly prestressed T0 contact: the patch breaks at once when the prestress
reaches its strength; ``cracks_supershear_rest.toml`` is the control, a weaker patch that breaks early,
meant to grow from rest into the critical crack as the load rises.  The table's ``sweep`` column names the
sweep.  Its main front is the first front that
nucleated in the patch running toward the far edge (+x, the longer side); ``rupture.transition`` gives,
for it, S as measured (``andrews_s``), Andrews' L_c and L_andrews = f(S) L_c, the measured transition
distance L_trans (the birth of a daughter ahead of its tip, from its nucleation) and the speed the
supershear front settled at.  Lengths in a, speeds in c_r.
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis import rupture
from parslip.analysis.fronts import band_of, wave_speeds
from parslip.model.physics import ROW_HEIGHT
from parslip.plot.figures import pyplot, save

from . import points, provenance, sweeps, write

COLS = ["sweep", "point", "rows", "v0", "patch_delta_b", "patch_width", "launch", "S", "tau0_over_taup", "L_c",
        "L_trans", "L_andrews", "ratio", "trans_by", "L_daughter", "L_fast", "room", "reflection", "v_super",
        "v_super_over_c_s", "band", "main_band", "bottom_kn", "damping", "zeta"]


def main_front(run, reach: float = 0.05):
    """The first front nucleated inside the nucleation patch (the scene's last patch, widened by 2 sites)
    that runs toward +x and gets ``reach`` (l) beyond the patch: the rupture of the contact, not the patch's
    own early breaks (which stop at its edge); None when there is none."""
    lo, hi = run.scene["interface.patch"][-1]["x"]
    pad = 2.0 / float(run.scene["lattice.top_cols"])
    cand = [f for f in run.fronts() if f.direction > 0 and lo - pad <= f.nucleation_x <= hi + pad
            and f.x_far >= hi + reach]
    return min(cand, key=lambda f: f.nucleation_time) if cand else None


def _row(sweep: str, row: dict, run) -> dict:
    sc = run.scene if run is not None else {}
    patch = (sc.get("interface.patch") or [{}])[-1]
    l = float(sc.get("lattice.top_cols", math.nan))
    out = {"sweep": sweep, "point": row["point"], "rows": sc.get("lattice.top_rows"), "v0": sc.get("drive.v0"),
           "patch_delta_b": patch.get("delta_b"),
           "patch_width": (patch["x"][1] - patch["x"][0]) * l if "x" in patch else math.nan,
           "bottom_kn": sc.get("material.bottom_kn"), "damping": sc.get("time.damping"),
           "zeta": sc.get("time.zeta"),
           "scene": row["scene"], "commit": row["commit"]}
    front = main_front(run) if run is not None else None
    if front is None:
        return {**out, **{c: math.nan for c in COLS if c not in out}, "band": None, "main_band": None,
                "trans_by": None}
    lo, hi = patch["x"]
    # how far the front can run: to the first patch beyond this one (the strong far edge), or the edge
    far = min([p["x"][0] for p in sc["interface.patch"][:-1] if p["x"][0] > hi] + [1.0])
    room = (far - 0.5 * (lo + hi)) * l
    tr = rupture.transition(run, front, origin=0.5 * (lo + hi), beyond=hi, before=far)
    waves = wave_speeds(run)
    h = float(sc["lattice.top_rows"]) * ROW_HEIGHT
    # The transition distance: a daughter's birth when the catalogue separates one from the main front, else
    # where the main front's own tip went above c_s and stayed (a daughter born a few sites ahead merges
    # into it; the catalogue then holds one front).
    by = "daughter" if math.isfinite(tr["L_trans"]) else ("tip above c_s" if math.isfinite(tr["L_fast"]) else None)
    L = tr["L_trans"] if by == "daughter" else tr["L_fast"]
    return {**out, "launch": tr["launch"], "S": tr["S"], "tau0_over_taup": tr["tau_0"] / tr["tau_peak"],
            "L_c": tr["L_c"],
            "L_trans": L, "L_andrews": tr["L_andrews"], "ratio": L / tr["L_andrews"], "trans_by": by,
            "L_daughter": tr["L_trans"], "L_fast": tr["L_fast"], "room": room,
            "reflection": 2 * h / math.sqrt(waves["c_l"] ** 2 - 1.0),
            "v_super": tr["v_super"], "v_super_over_c_s": tr["v_super"] / waves["c_s"],
            "band": band_of(tr["v_super"], waves), "main_band": front.band,
            "_front": front, "_run": run, "_tr": tr}


def andrews_axes(s_max: float):
    """A figure whose axes hold Andrews' L_trans / L_c = 9.8 (1.77 - S)^-3 over 0 <= S <= s_max and its
    factor-1.5 band: what a transition study's points are set beside."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    S = np.linspace(0.0, s_max, 300)
    f = rupture.andrews_f(S)
    ax.plot(S, f, "k-", lw=1, label="Andrews (1976), Xia et al. (2004): 9.8 (1.77 - S)$^{-3}$")
    ax.fill_between(S, f / 1.5, f * 1.5, color="0.85", label="factor 1.5")
    return fig, ax


def transition_figure(rows, img, source):
    """L_trans / L_c against S, beside Andrews' 9.8 (1.77 - S)^-3 and its factor-1.5 band."""
    fig, ax = andrews_axes(1.72)
    for sweep, c in zip(sorted({r["sweep"] for r in rows}), ("tab:blue", "tab:orange", "tab:green")):
        mine = [r for r in rows if r["sweep"] == sweep and np.isfinite(r["S"])]
        for by, m in (("daughter", "o"), ("tip above c_s", "s")):
            ok = [r for r in mine if r["trans_by"] == by]
            if ok:
                ax.plot([r["S"] for r in ok], [r["L_trans"] / r["L_c"] for r in ok], m, color=c,
                        mfc="none" if m == "s" else c, label=f"{sweep}: {by}")
        for r in mine:
            if r["trans_by"] is None:       # no transition: the room it had, as a lower bound
                ax.plot(r["S"], r["room"] / r["L_c"], "^", color=c, mfc="none")
    ax.set_yscale("log")
    ax.axvline(rupture.ANDREWS_S_2D, color="k", ls=":", lw=0.8)
    ax.text(rupture.ANDREWS_S_2D, 1.5, " S = 1.77: no transition (2D)", fontsize=6, rotation=90, va="bottom")
    for r in rows:                    # the nucleation patch's edge: no transition can be measured nearer
        if np.isfinite(r["S"]) and np.isfinite(r["L_c"]):
            ax.plot(r["S"], 0.5 * r["patch_width"] / r["L_c"], "_", color="0.3", ms=8)
    ax.set_xlim(0.0, 2.7)
    ax.set_xlabel("S measured on the run (andrews_s)")
    ax.set_ylabel("transition distance / L_c")
    ax.legend(fontsize=6)
    ax.set_title("supershear transition on the matched pair, l = 500 a\n"
                 "-: the patch's edge; ^: no transition within the run's room", fontsize=7)
    return save(fig, img, "cracks_supershear_transition", source)


def tips_figure(rows, img, source):
    """Each run's main front and its daughter: distance from nucleation against time since it, with the
    slopes of c_s and the block's c_l."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    waves = None
    for i, r in enumerate(rows):
        if "_front" not in r or r["sweep"] != "cracks_supershear":
            continue
        run, f, tr = r["_run"], r["_front"], r["_tr"]
        waves = waves or wave_speeds(run)
        l = float(run.scene["lattice.top_cols"])
        t0, x0 = f.nucleation_time, f.nucleation_x
        line, = ax.plot((np.asarray(f.tip["t"]) - t0) * l, (np.asarray(f.tip["x"]) - x0) * l, lw=1,
                        label=f"S = {r['S']:.2f}")
        if tr["daughter"] is not None:
            d = run.fronts()[tr["daughter"]]
            ax.plot((np.asarray(d.tip["t"]) - t0) * l, (np.asarray(d.tip["x"]) - x0) * l, ":", lw=1.5,
                    color=line.get_color())
    if waves:
        t = np.array([0.0, 250.0])
        for key, ls in (("c_s", "--"), ("c_l", "-.")):
            ax.plot(t, waves[key] * t, ls, color="0.5", lw=0.8, label=f"{key} = {waves[key]:.3g} c_r")
    ax.set_xlabel("time since its first break (a / c_r)")
    ax.set_ylabel("tip's distance from its first break (a)")
    ax.legend(fontsize=6)
    ax.set_title("cracks_supershear: main fronts (solid) and daughters (dotted)", fontsize=8)
    return save(fig, img, "cracks_supershear_tips", source)


def tabulate(runs: str, img: str, tables: str) -> str:
    """cracks_supershear.csv (a row per run, ``COLS`` then scene and commit) and the two figures; returns
    the Markdown table."""
    rows = [_row(os.path.basename(d), row, run) for d in sweeps(runs, "supershear") for row, run in points(d)]
    source = provenance(rows)
    md = write(rows, COLS, os.path.join(tables, "cracks_supershear.csv"))
    transition_figure(rows, img, source)
    tips_figure(rows, img, source)
    return md
