"""Study 4 of docs/studies/weakening.md: the supershear fronts of Andrews' runs against Kammer et al.'s equation of
motion (Sci. Adv. 2018, Eq. 1), evaluated by ``analysis.lefm`` at the lattice's c_s/c_l (the classical solid
of that ratio, as they evaluate it).

For each run of ``run/studies/weakening_andrews*.toml`` whose front turned supershear before the reflected
wave, on each side: the front's speed by straight lines through the arrivals of 20 sites
(``transition.window_speeds``) from L_trans to the farthest distance free of the reflected wave and of the
strong edge (less a window); the table's row is the last such window (``length``: its middle, the
half-length of the bilateral crack then; ``v`` the mean of the two sides), beside Eq. 1's speed at that
half-length, ``v_eq1`` = ``lefm.kammer_speed``(length / l_0, r), with r = ``tau0_over_taup`` = (tau_0 - tau_r)
/ (tau_p - tau_r) and l_0 = rho c_s^2 Gamma / (tau_p - tau_r)^2 (the scene's law scales).  Lengths in a,
speeds in c_r.
"""
from __future__ import annotations

import math
import os

import numpy as np

from parslip.analysis import lefm, transition
from parslip.analysis.fronts import wave_speeds
from parslip.model.physics import DENSITY
from parslip.plot.figures import pyplot, save

from . import provenance, write
from .andrews import rows as andrews_rows

COLS = ["sweep", "point", "tau0_over_taup", "length", "v", "v_eq1", "v_over_c_s", "v_eq1_over_c_s", "l_0",
        "length_over_l0", "l_m_over_l0", "S", "L_trans", "nucleation", "zeta", "damping", "hold", "bottom_kn"]
WINDOW = 20


def l0(scales: dict, c_s: float) -> float:
    """Kammer et al.'s l_0 = rho c_s^2 Gamma / (tau_p - tau_r)^2 (a) from the law's scales (tau in rho c_r^2,
    Gamma in m c_r^2 / a, c_s in c_r): rho c_s^2 Gamma / (rho (tau_p - tau_r))^2."""
    return c_s ** 2 * scales["Gamma"] / (DENSITY * (scales["tau_p"] - scales["tau_r"]) ** 2)


def speeds(r: dict) -> tuple[np.ndarray, np.ndarray]:
    """(length, v) of the run's supershear front, the two sides' window speeds averaged where both have one."""
    m, g = r["_m"], r["_m"]["geometry"]
    until = min(g["reflection"], g["room"] - WINDOW, m["uniform"])
    per = [transition.window_speeds(s["r"], s["t"], r["L_trans"], until, WINDOW) for s in m["sides"]]
    n = min(len(p[0]) for p in per)
    if n == 0:
        return np.array([]), np.array([])
    return np.mean([p[0][:n] for p in per], axis=0), np.mean([p[1][:n] for p in per], axis=0)


def _row(r: dict) -> dict | None:
    if "_m" not in r or not math.isfinite(r["L_trans"]):
        return None
    L, v = speeds(r)
    if not len(L):
        return None
    run, sc = r["_run"], r["_m"]["scales"]
    c_s, c_l = (wave_speeds(run)[k] for k in ("c_s", "c_l"))
    solid = lefm.Solid(c_s / c_l)
    ratio = (sc["tau_0"] - sc["tau_r"]) / (sc["tau_p"] - sc["tau_r"])
    lz = l0(sc, c_s)
    v_eq1 = float(lefm.kammer_speed(L[-1] / lz, ratio, solid)) * c_s
    return {"sweep": r["sweep"], "point": r["point"], "tau0_over_taup": ratio, "length": float(L[-1]),
            "v": float(v[-1]), "v_eq1": v_eq1, "v_over_c_s": float(v[-1]) / c_s, "v_eq1_over_c_s": v_eq1 / c_s,
            "l_0": lz, "length_over_l0": float(L[-1]) / lz,
            "l_m_over_l0": lefm.minimal_supershear_length(ratio, solid)[0], "S": r["S"],
            "L_trans": r["L_trans"], "nucleation": r["nucleation"], "zeta": r["zeta"], "damping": r["damping"],
            "hold": r["hold"], "bottom_kn": r["bottom_kn"], "scene": r["scene"], "commit": r["commit"],
            "_curve": (L / lz, v / c_s), "_solid": solid}


def figure(ks, img, source):
    """Each run's supershear speed against its half-length over l_0, beside Eq. 1 at its r."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for i, k in enumerate(ks):
        x, v = k["_curve"]
        line, = ax.plot(x, v, "o-", ms=3, lw=0.8,
                        label=f"{k['sweep'].replace('weakening_andrews_', '').replace('weakening_andrews', 'main')} "
                              f"{k['point']}, {k['nucleation']}, "
                              f"r = {k['tau0_over_taup']:.2f}")
        grid = np.geomspace(5.0, 400.0, 60)
        ax.plot(grid, lefm.kammer_speed(grid, k["tau0_over_taup"], k["_solid"]), "--", lw=0.8,
                color=line.get_color())
    if ks:
        c_l = 1.0 / ks[0]["_solid"].k
        ax.axhline(c_l, color="0.5", lw=0.6, ls="-.")
        ax.axhline(math.sqrt(2.0), color="0.5", lw=0.6, ls=":")
    ax.set_xscale("log")
    ax.set_xlabel("half-length L / l_0")
    ax.set_ylabel("front speed / c_s")
    ax.legend(fontsize=6)
    ax.set_title("supershear fronts (points) and Kammer et al. (2018) Eq. 1 at their r (dashed);\n"
                 "dash-dot: c_l, dotted: sqrt(2) c_s", fontsize=7)
    return save(fig, img, "weakening_kammer_speeds", source)


def tabulate(runs: str, img: str, tables: str) -> str:
    """weakening_kammer.csv (a row per run that turned supershear) and its figure; returns the Markdown."""
    ks = [k for k in (_row(r) for r in andrews_rows(runs)) if k is not None]
    md = write(ks, COLS, os.path.join(tables, "weakening_kammer.csv"))
    figure(ks, img, provenance(ks))
    return md
