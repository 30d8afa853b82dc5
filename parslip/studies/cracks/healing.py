"""Healing with contact (docs/studies/cracks.md, section 4): the heal_time and heal_speed studies of
docs/studies/interfaces.md re-run with and without ``interface.contact``, to tell which of their findings
were the sinking of unbonded sites.

In the paper's interface a top site whose bond has broken feels no force from the substrate, so under F_N a
block whose bonds wait to re-form sinks (at about F_N/(N zeta) under absolute damping, N the block's nodes)
and can leave the delta0 window within which a bond re-forms.  Each sweep here runs its points at contact 0
(the paper, as the old study ran) and with the contact on; per run the table holds what the old tables
held (the first crossing front's kind, speed and width, the bonds re-formed before it crossed, fronts,
crossings, mu_s) and what tells the sinking apart: every re-formation of the drive, the slip events, the
share of bonds intact at the end, and the deepest any block site went below its start
(``analysis.friction.sinking``).

Sweeps (``run/studies/cracks_healing*.toml``): ``_time`` and ``_speed`` are the old sweeps on the old scene
(l = 100 a), ``_stiff`` a stiffer contact on the rows that change, ``_l500`` T0 rows on the resolved
identical-solid scene (run/cracks_l500.toml, with k_x = 0.1 and the old damping).
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis.friction import first_crossing, reformations, sinking
from parslip.plot.figures import pyplot, save

from . import points, provenance, sweeps, write

# The columns of cracks_healing.csv (then scene and commit).
COLS = ["sweep", "point", "l", "rows", "drive.mode", "drive.v0", "swept", "value", "contact", "kind", "mean v",
        "width a", "re-formed before crossing", "re-formations", "n_fronts", "n_crossed", "slip events", "mu_s",
        "intact at end", "max sink a", "window l/c_r"]
# What each sweep file varies besides the contact (the sweep's stem after cracks_healing_).
SWEPT = {"time": "interface.heal_time", "speed": "interface.heal_speed", "stiff": "interface.heal_time",
         "l500": "interface.heal_time"}
# The sinking drawn: the T0 rows with a delay past the old threshold, at both scenes.
SINK_DRAWN = (2.0, 5.0)
SINK_SWEEPS = ("cracks_healing_time", "cracks_healing_l500")


def rebond_window(scene: dict) -> float:
    """How long (l/c_r) a top site sliding at the drive's speed stays within delta0 of one substrate site
    while the contact holds it up, the longest a claim can last: the site rests p = F_N/(N_s k_c) below
    delta0 (its share of the load over the contact's stiffness, N_s = top_cols sites), so its path cuts the
    delta0 disc around a substrate site in a chord 2 sqrt(2 delta0 p - p^2) (a), crossed at v0 l a per l/c_r
    (v0 in c_r, l = top_cols a).  A delay longer than this cannot be served while the block slides.  NaN for
    contact 0 (nothing holds the site up) or no drive."""
    kc, v0, n = scene.get("interface.contact", 0.0), scene.get("drive.v0", 0.0), scene.get("lattice.top_cols", 0)
    if not (kc > 0 and v0 > 0 and n > 0):
        return math.nan
    p, d0 = min(scene["load.FN"] / (n * kc), scene["interface.delta0"]), scene["interface.delta0"]
    return 2 * math.sqrt(2 * d0 * p - p * p) / (v0 * n)


def row_of(stem: str, row: dict, run) -> dict:
    """One table row: the point's keys and the measures of its run (NaN and "-" for a failed point)."""
    key = SWEPT[stem.removeprefix("cracks_healing_")]
    sc = run.scene if run is not None else {}
    r = {"sweep": stem, "point": row["point"], "swept": key, "value": row.get(key, sc.get(key)),
         "contact": row.get("interface.contact", sc.get("interface.contact", 0.0)),
         "l": sc.get("lattice.top_cols", math.nan), "rows": sc.get("lattice.top_rows", math.nan),
         "drive.mode": sc.get("drive.mode", "-"), "drive.v0": sc.get("drive.v0", math.nan),
         "window l/c_r": rebond_window(sc), "scene": row.get("scene", ""), "commit": row.get("commit", "")}
    if run is None:
        return {**r, **{c: math.nan for c in COLS if c not in r}, "kind": "failed"}
    fr = run.fronts()
    f = first_crossing(run, fr)
    intact = np.asarray(run.interface["intact"])
    return {**r, "kind": f.kind if f else "-", "mean v": abs(f.mean_speed) if f else math.nan,
            "width a": f.width if f else math.nan,
            "re-formed before crossing": reformations(run, f.nucleation_time, f.t_end) if f else -1,
            "re-formations": reformations(run), "n_fronts": len(fr), "n_crossed": row.get("n_crossed", math.nan),
            "slip events": len(run.slip_events()), "mu_s": row.get("mu_s", math.nan),
            "intact at end": float(intact[-1].mean()) if intact.size else math.nan,
            "max sink a": float(max(0.0, np.max(sinking(run), initial=0.0)))}


def sink_figure(curves: list, img: str, source) -> list[str]:
    """The deepest block site below its start against time, per run drawn (label, t, depth, colour, dashed),
    with the depth at which a sunk site has left the re-bonding window."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 5.2))
    for label, t, d, colour, dashed in curves:
        ax.plot(t, d, color=colour, ls="--" if dashed else "-", lw=1.1, label=label)
    ax.axhline(1.0, color="0.4", ls=":", lw=0.8)
    ax.text(0.01, 1.1, "about 1 a: a sunk site has left the delta0 window", fontsize=7,
            transform=ax.get_yaxis_transform())
    ax.set_xlabel("t (l/c_r)")
    ax.set_ylabel("deepest block site below its start (a)")
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_ylim(bottom=-0.05)                      # a site may stand a little above its start: no more
    ax.legend(fontsize=6, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    ax.set_title("T0 with a healing delay: contact 0 dashed, contact on solid", fontsize=8)
    return save(fig, img, "cracks_healing_sink", source)


def fronts_figure(rows: list[dict], img: str, source) -> list[str]:
    """Fronts and re-formations against heal_time, per scene and drive, contact 0 (open, dashed) and on
    (filled); the stiffness rows are left to the table."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(8.5, 3.8))
    sel = [r for r in rows if r["sweep"] in ("cracks_healing_time", "cracks_healing_l500") and r["kind"] != "failed"]
    groups = sorted({(r["l"], r["drive.mode"]) for r in sel})
    for i, (l, mode) in enumerate(groups):
        for on in (False, True):
            pts = sorted((r["value"], r["n_fronts"], r["re-formations"]) for r in sel
                         if (r["l"], r["drive.mode"]) == (l, mode) and (r["contact"] > 0) == on)
            if not pts:
                continue
            x, nf, nr = zip(*pts)
            style = dict(color=f"C{i}", marker="o", mfc=f"C{i}" if on else "none", ls="-" if on else "--",
                         label=f"l = {l:g} a, {mode}, contact {'on' if on else '0'}")
            axes[0].plot(x, nf, **style)
            axes[1].plot(x, np.maximum(nr, 0.5), **style)
    axes[0].set_ylabel("fronts in the run")
    axes[1].set_ylabel("bonds re-formed in the run (0 drawn at 0.5)")
    axes[1].set_yscale("log")
    for ax in axes:
        ax.set_xlabel("interface.heal_time (l/c_r)")
        ax.legend(fontsize=6)
    fig.suptitle("heal_time with and without contact (l = 100: 100 l/c_r; l = 500: 30 l/c_r)", fontsize=8)
    return save(fig, img, "cracks_healing_fronts", source)


def tabulate(runs: str, img: str, tables: str) -> str:
    """Write cracks_healing.csv and the figures; return the Markdown table."""
    rows, curves = [], []
    for d in sweeps(runs, "healing"):
        stem = os.path.basename(d)
        for row, run in points(d):
            rows.append(row_of(stem, row, run))
            r = rows[-1]
            if run is not None and r["drive.mode"] == "shear" and r["value"] in SINK_DRAWN and stem in SINK_SWEEPS:
                colour = f"C{SINK_DRAWN.index(r['value']) + 2 * SINK_SWEEPS.index(stem)}"
                curves.append((f"l = {r['l']:g} a, heal_time {r['value']:g}, contact {r['contact']:g}", run.times,
                               sinking(run), colour, r["contact"] == 0))
    source = provenance(rows)
    md = write(rows, COLS, os.path.join(tables, "cracks_healing.csv"))
    if curves:
        sink_figure(curves, img, source)
    fronts_figure(rows, img, source)
    return md
