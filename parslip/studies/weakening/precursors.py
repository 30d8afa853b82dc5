"""Study 5 of docs/studies/weakening.md: precursors that are cracks.

The loader study of docs/studies/cracks.md (section 2: the push through a soft loader at three loading heights,
``drive.rows``) on the slip-weakening interface, whose broken sites carry Coulomb friction
(``interface.contact_friction``) and re-form only after ``interface.heal_time``, at three normal loads, swept
by ``run/studies/weakening_precursors*.toml``.  A precursor is a burst of breaks that grew the slipped region
from the loaded edge and stopped inside the contact before the first burst that reached the far edge (the
contact's first slip whole, ``t_slip``; ``analysis.arrest.edge_cracks``: breaks no more than ``GAP`` a/c_r
apart, at least Lambda of them): behind its tip the sites stay broken, slipping at the residual,
so the catalogue of fronts would cut it where it runs through them.  For every run: each precursor's length
from the loaded edge over the law's Lambda (``rupture.law_scales``: 9 pi/16 M Gamma/(tau_p - tau_r)^2 at rest
under the run's F_N), F_T/F_N at its arrest (mu at the first frame after its last break), its speed (the sites
it spans over its duration), whether a P wave it sent could have come back to the interface off the block's
far face before it stopped (its duration against 2 H/c_l, H the shorter block's height), and the arrest the
static criterion predicts (``analysis.arrest.arrest_prediction``: the edge crack unloaded from the traction
before its first break to the residual after its last stops where its static G falls to Gamma; Kammer et al.,
Tribol. Lett. 2015; Bayart et al., Nat. Phys. 2016) with Gamma the law's fracture energy, no parameter
fitted.  Per normal load and block height (``block_rows``: the main sweep's and the
tall control's apart), every loading height together (Katano et al., Sci. Rep. 2014, Fig. 2: a line per F_z
whatever the height and the drive speed), the straight line L/Lambda = slope * F_T/F_N +
intercept with its r^2 (``cracks.precursors.line_fit``); beside it each run's own line (``run_slope``,
``run_r2``: one loading height, as Rubinstein et al.'s Fig. 3 draws one loading configuration).

Tables: ``weakening_precursors.csv`` a row per run (``F_N``, ``height``, ``n_precursors``, ``n_over_3_lambda``,
the load's ``slope`` and ``r2``, ``median_predicted_over_measured``), ``weakening_precursors_arrests.csv`` a row
per precursor; figures ``img/weakening_precursors_length.png`` (length against F_T/F_N, a line per F_N) and
``img/weakening_precursors_prediction.png`` (predicted against measured arrest).  Lengths in a unless named
over Lambda, times in l/c_r, speeds in c_r.
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis import table
from parslip.analysis.arrest import arrest_prediction, edge_cracks
from parslip.analysis.fronts import wave_speeds
from parslip.model.physics import ROW_HEIGHT
from parslip.plot.figures import pyplot, save

from ..cracks.precursors import _mu_at, gather, height_of, line_fit, max_gap
from . import provenance, sweeps, write
from .andrews import scales

# The readings the runs depart from the defaults in, named as columns so that the tables declare them.
READING_COLS = ["reform_x0", "contact", "bottom_kn", "damping", "zeta"]
COLS = ["sweep", "point", "F_N", "height", "block_rows", "rows", "n_bursts", "n_crossed", "t_slip", "n_precursors",
        "n_over_3_lambda", "n_before_reflection", "catalogue_arrested", "catalogue_max_over_lambda",
        "min_length_over_lambda", "max_length_over_lambda",
        "median_speed", "slope", "intercept", "r2", "n_fit", "run_slope", "run_r2", "median_predicted_over_measured",
        "n_predicted",
        "n_within_2", "Lambda", "tau_p", "tau_r", "Gamma", "reflection_time", "first_break", "kx", "softening",
        "contact_friction", "heal_time", "record_end", "status"] + READING_COLS
ARREST_COLS = ["sweep", "point", "F_N", "height", "block_rows", "precursor", "first_x", "nucleation_time",
               "arrest_time", "duration", "breaks", "span", "speed", "before_reflection", "mu_arrest", "length",
               "length_over_lambda", "predicted_over_lambda", "predicted_over_measured", "G_over_Gamma_at_arrest",
               "tau_r_measured", "Lambda", "Gamma"] + READING_COLS
HEIGHT_MARKS = {"low": "o", "mid": "s", "high": "^", "face": "D"}
WITHIN = 2.0        # the target's band: predicted within a factor 2 of measured
# The longest quiet time inside one precursor (a/c_r): a tip at 0.02 c_r breaks a site every 50 a/c_r, and one
# at 0.4 c_r crosses 20 sites that have not re-formed (no break there) in 50 a/c_r; half the delay
# (heal_time = 100 a/c_r), so that a stretch a precursor broke has not re-formed when the next burst starts.
GAP = 50.0


def reflection_time(run) -> float:
    """2 H / c_l (l/c_r): when a P wave sent from the interface first comes back to it off the far face of
    the shorter block (H its height, rows * ROW_HEIGHT a; the top is loaded, the substrate's last row fixed:
    both reflect)."""
    s = run.scene
    h = float(min(s["lattice.top_rows"], s["lattice.bottom_rows"])) * ROW_HEIGHT
    return 2.0 * h / wave_speeds(run)["c_l"] / float(s["lattice.top_cols"])


def run_arrests(row: dict, run) -> tuple[dict, list[dict]]:
    """The run's row (without its load's fit) and a row per precursor (module docstring)."""
    s, sc = run.scene, scales(run)
    lam, ns, l = sc["Lambda"], len(run.x), float(s["lattice.top_cols"])
    refl = reflection_time(run)
    head = {"sweep": row.get("sweep", ""), "point": row["point"], "F_N": float(s["load.FN"]),
            "height": height_of(s["drive.rows"], int(s["lattice.top_rows"])), "block_rows": int(s["lattice.top_rows"]),
            "scene": row["scene"], "commit": row["commit"], "reform_x0": s["interface.reform_x0"],
            "contact": s["interface.contact"], "bottom_kn": s["material.bottom_kn"], "damping": s["time.damping"],
            "zeta": s["time.zeta"]}
    bursts = edge_cracks(run, GAP / l, max(int(round(lam)), 1))
    # Precursors come before the contact first slips whole: the first burst that reached the far edge.
    t_slip = min((c.nucleation_time for c in bursts if not c.arrested), default=math.inf)
    arrests = []
    for i, p in enumerate(c for c in bursts if c.arrested and c.arrest_time < t_slip):
        pred = arrest_prediction(run, p, gamma=sc["Gamma"])
        length, dur = p.arrest_length * l, p.arrest_time - p.nucleation_time
        arrests.append({**head, "precursor": i, "first_x": p.first_x * l, "nucleation_time": p.nucleation_time,
                        "arrest_time": p.arrest_time, "duration": dur, "breaks": p.breaks, "span": p.span,
                        "speed": p.span / (dur * l) if dur > 0 else math.inf, "before_reflection": dur < refl,
                        "mu_arrest": _mu_at(run, p.arrest_time), "length": length, "length_over_lambda": length / lam,
                        "predicted_over_lambda": pred["L_predicted"] / lam,
                        "predicted_over_measured": pred["L_predicted"] / length,
                        "G_over_Gamma_at_arrest": pred["G_at_arrest_over_Gamma"], "tau_r_measured": pred["tau_r"],
                        "Lambda": lam, "Gamma": sc["Gamma"]})
    # The catalogue of fronts on the same run, as the loader study of docs/studies/cracks.md counts precursors.
    cat = [p for p in run.precursors(max_gap=max_gap(run)) if p.arrest_time < t_slip]
    L = [a["length_over_lambda"] for a in arrests]
    ratio = [a["predicted_over_measured"] for a in arrests if math.isfinite(a["predicted_over_measured"])]
    nan = math.nan
    status = str(run.attrs.get("status", ""))
    out = {**head, "rows": "-".join(str(r) for r in s["drive.rows"]) or "all", "n_bursts": len(bursts),
           "record_end": float(run.times[-1]), "status": status.split(":")[0],
           "n_crossed": sum(not c.arrested for c in bursts), "t_slip": t_slip, "n_precursors": len(arrests),
           "catalogue_arrested": len(cat),
           "catalogue_max_over_lambda": max((p.arrest_length * l / lam for p in cat), default=nan),
           "n_over_3_lambda": sum(x > 3.0 for x in L),
           "n_before_reflection": sum(a["before_reflection"] for a in arrests),
           "min_length_over_lambda": min(L, default=nan), "max_length_over_lambda": max(L, default=nan),
           "median_speed": float(np.median([a["speed"] for a in arrests])) if arrests else nan,
           "median_predicted_over_measured": float(np.median(ratio)) if ratio else nan, "n_predicted": len(ratio),
           "n_within_2": sum(1 / WITHIN <= r <= WITHIN for r in ratio), "Lambda": lam, "tau_p": sc["tau_p"],
           "tau_r": sc["tau_r"], "Gamma": sc["Gamma"], "reflection_time": refl,
           "first_break": run.first_break[0], "kx": s["interface.kx"], "softening": s["interface.softening"],
           "contact_friction": s["interface.contact_friction"], "heal_time": s["interface.heal_time"]}
    return out, arrests


def group(a: dict) -> tuple:
    """What one line spans: a normal load on one block height (``block_rows``), every loading height."""
    return a["F_N"], a["block_rows"]


def load_fits(arrests: list[dict]) -> dict:
    """``group`` -> ``line_fit`` of length_over_lambda against mu_arrest over its precursors, every height."""
    return {k: line_fit([a["mu_arrest"] for a in arrests if group(a) == k],
                        [a["length_over_lambda"] for a in arrests if group(a) == k])
            for k in sorted({group(a) for a in arrests})}


def length_figure(arrests: list[dict], fit: dict, img: str, source: dict):
    """Arrest length over Lambda against F_T/F_N at the arrest: a colour per normal load with its line, a marker
    per loading height; open markers: a precursor that ran longer than the reflection time."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for k, (key, f) in enumerate(fit.items()):
        c, mine = f"C{k}", [a for a in arrests if group(a) == key]
        name = f"F_N = {key[0]:g}, {key[1]} rows"
        for h, mk in HEIGHT_MARKS.items():
            label = f"{name}, {h}"
            for early in (True, False):
                sel = [a for a in mine if a["height"] == h and a["before_reflection"] == early]
                if sel:
                    ax.plot([a["mu_arrest"] for a in sel], [a["length_over_lambda"] for a in sel], mk, color=c,
                            mfc=c if early else "none", ms=4, label=label)
                    label = None                    # one legend entry per height, filled or open
        if math.isfinite(f["slope"]):
            xs = np.array([min(a["mu_arrest"] for a in mine), max(a["mu_arrest"] for a in mine)])
            ax.plot(xs, f["slope"] * xs + f["intercept"], "-", color=c, lw=1,
                    label=f"{name}: slope {f['slope']:.3g}, r2 {f['r2']:.2f} ({f['n_fit']})")
    ax.axhline(3.0, color="k", ls=":", lw=0.8)
    ax.set_xlabel("F_T / F_N at the arrest")
    ax.set_ylabel("arrest length / Lambda")
    ax.set_title("a line per F_N, every height (dotted: 3 Lambda; open: ran past 2H/c_l)", fontsize=8)
    if arrests:
        ax.legend(fontsize=6)
    return save(fig, img, "weakening_precursors_length", source)


def prediction_figure(arrests: list[dict], img: str, source: dict):
    """The static criterion's arrest against the measured one (a colour per normal load), with the factor-2
    band; the precursors whose G never reached Gamma are left out (counted in the title)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 4.5))
    pts = [a for a in arrests if math.isfinite(a["predicted_over_lambda"])]
    for k, key in enumerate(sorted({group(a) for a in arrests})):
        for h, mk in HEIGHT_MARKS.items():
            sel = [a for a in pts if group(a) == key and a["height"] == h]
            if sel:
                ax.plot([a["length_over_lambda"] for a in sel], [a["predicted_over_lambda"] for a in sel], mk,
                        color=f"C{k}", ms=4, label=f"F_N = {key[0]:g}, {key[1]} rows, {h}")
    top = max([a["length_over_lambda"] for a in pts] + [a["predicted_over_lambda"] for a in pts] + [10.0])
    xs = np.array([0.1, 2 * top])
    ax.plot(xs, xs, "k-", lw=0.6)
    for f in (WITHIN, 1 / WITHIN):
        ax.plot(xs, f * xs, "k:", lw=0.6)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("measured arrest length / Lambda")
    ax.set_ylabel("predicted (static G falls to Gamma) / Lambda")
    ax.set_title(f"{len(pts)} of {len(arrests)} precursors reach G = Gamma (dotted: factor 2)", fontsize=8)
    if pts:
        ax.legend(fontsize=6)
    return save(fig, img, "weakening_precursors_prediction", source)


def tabulate(runs: str, img: str, tables: str) -> str:
    """Both tables and both figures (module docstring); returns the Markdown of the runs' table."""
    rows, arrests = gather(sweeps(runs, "precursors"), run_arrests)
    fit = load_fits(arrests)
    nan = {"slope": math.nan, "intercept": math.nan, "r2": math.nan, "n_fit": 0}
    for r in rows:
        r.update(fit.get(group(r), nan))
        own = [a for a in arrests if (a["sweep"], a["point"]) == (r["sweep"], r["point"])]
        r.update({f"run_{k}": v for k, v in line_fit([a["mu_arrest"] for a in own],
                                                     [a["length_over_lambda"] for a in own]).items()
                  if k in ("slope", "r2")})
    table.write_csv(os.path.join(tables, "weakening_precursors_arrests.csv"), ARREST_COLS + ["scene", "commit"],
                    arrests)
    source = provenance(rows)
    length_figure(arrests, fit, img, source)
    prediction_figure(arrests, img, source)
    return write(rows, COLS, os.path.join(tables, "weakening_precursors.csv"))
