"""The friction study's maps, figures and tables (docs/studies/friction.md), from its sweeps' outputs.

    for s in loading rate stiffness_push stiffness_shear; do
        mpiexec -n 2 parslip sweep run/studies/friction_$s.toml -o out/friction/$s
    done
    python postprocess/friction_study.py --dir out/friction -o docs/studies/img --tables docs/studies

Writes into OUT: the maps (parslip map) of mu_s and of the rupture kind over F_N and the loading, and
over F_N and k_x; F_s(F_N) per loading with its straight-line fit; mu(t) of three points; and the
summary tables as CSV (friction_<sweep>.csv, in --tables).  Prints the Markdown tables the page quotes.
"""
import argparse
import math
import os
import shutil

import numpy as np

from parslip.analysis import table
from parslip.analysis.results import Run
from parslip.plot import maps
from parslip.plot.figures import fig_friction, save

SWEEPS = ("loading", "rate", "stiffness_push", "stiffness_shear")
MODES = ("push", "pull", "shear")
FIGURE_POINTS = {"friction_shear_FN4": ("loading", {"drive.mode": "shear", "load.FN": 4.0}),
                 "friction_shear_FN0.25": ("loading", {"drive.mode": "shear", "load.FN": 0.25}),
                 "friction_pull_FN1": ("loading", {"drive.mode": "pull", "load.FN": 1.0})}


def rows(tab, **where):
    keep = maps.select(tab, where) if where else range(len(tab["point"]))
    return [{c: tab[c][i] for c in tab} for i in keep]


def fit(fn, fs):
    """F_s = F_0 + mu_i F_N by least squares: (F_0, mu_i)."""
    b, a = np.polyfit(np.asarray(fn, float), np.asarray(fs, float), 1)
    return a, b


def fs_figure(tab, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 4))
    lines = []
    for mode, c in zip(MODES, ("tab:blue", "tab:orange", "tab:green")):
        rs = rows(tab, **{"drive.mode": mode})
        ok = [r for r in rs if r["mu_s_window"] == "slip onset"]
        bound = [r for r in rs if r["mu_s_window"] == "record"]
        fn = [r["load.FN"] for r in ok]
        fs = [r["F_s"] for r in ok]
        ax.plot(fn, fs, "o", color=c, label=f"{mode}")
        ax.plot([r["load.FN"] for r in bound], [r["F_s"] for r in bound], "^", mfc="none", color=c)
        low = [(a, b) for a, b in zip(fn, fs) if a <= 2.0]
        if len(low) >= 2:
            f0, mu = fit(*zip(*low))
            xx = np.linspace(0, 4.2, 50)
            ax.plot(xx, f0 + mu * xx, "--", color=c, lw=0.8)
            lines.append((mode, f0, mu, len(low)))
    ax.plot([], [], "^", mfc="none", color="0.4", label="lower bound (no slip onset in the record)")
    ax.set_xlabel("F_N  (m c^2/a)")
    ax.set_ylabel("F_s = mu_s F_N  (m c^2/a)")
    ax.set_xlim(0, 4.3)
    ax.set_ylim(0, None)
    ax.legend(fontsize=7)
    ax.set_title("static friction force against normal load, v0/c_r = 1e-3;\ndashed: F_0 + mu_i F_N fitted "
                 "over F_N <= 2", fontsize=8)
    save(fig, out, "friction_Fs_FN", tab)
    os.remove(os.path.join(out, "friction_Fs_FN.pdf"))
    return lines


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dir", required=True, help="directory holding the sweeps' OUTDIRs (loading, rate, ...)")
    p.add_argument("-o", "--out", required=True, help="directory for the pictures")
    p.add_argument("--tables", help="directory for the summary tables, friction_<sweep>.csv (default: --out)")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    tabs = {}
    for s in SWEEPS:
        path = os.path.join(a.dir, s, "summary.csv")
        tabs[s] = table.read(path)
        os.makedirs(a.tables or a.out, exist_ok=True)
        shutil.copy(path, os.path.join(a.tables or a.out, f"friction_{s}.csv"))
    L = tabs["loading"]
    for color in ("mu_s", "F_s", "n_precursors"):
        maps.draw_map(L, "load.FN", "drive.mode", color, os.path.join(a.out, f"map_loading_{color}.png"),
                      title=f"{color} over F_N and the loading (v0/c_r = 1e-3); marker: rupture kind")
    for mode in ("push", "shear"):
        T = tabs[f"stiffness_{mode}"]
        for color in ("mu_s", "n_precursors"):
            maps.draw_map(T, "load.FN", "interface.kx", color,
                          os.path.join(a.out, f"map_stiffness_{mode}_{color}.png"),
                          title=f"{mode}: {color} over F_N and k_x (k_y = 3 k_x); marker: rupture kind")
    lines = fs_figure(L, a.out)
    for name, (sweep, where) in FIGURE_POINTS.items():
        r = rows(tabs[sweep], **where)[0]
        run = Run(os.path.join(a.dir, sweep, r["out"]))
        for path in fig_friction(run, a.out):
            if path.endswith(".pdf"):
                os.remove(path)
            else:
                os.replace(path, os.path.join(a.out, f"{name}.png"))
    cols = ["drive.mode", "load.FN", "mu_s", "mu_s_window", "F_s", "first_break_time", "mu_first_break",
            "slip_onset_time", "mu_sliding", "rupture_kind", "n_fronts", "n_crossed", "n_precursors",
            "precursor_arrest_mean", "precursor_arrest_max", "front_speed", "slip_per_event", "wall_s"]
    print("## loading\n")
    print(table.markdown(rows(L), cols, {"wall_s": "{:.1f}"}))
    print("\nF_s = F_0 + mu_i F_N fits (F_N <= 2, all with a slip onset):")
    for mode, f0, mu, n in lines:
        print(f"  {mode}: F_0 = {f0:.3f}, mu_i = {mu:.3f} ({n} points)")
    print("\n## rate\n")
    print(table.markdown(rows(tabs["rate"]), ["drive.mode", "drive.v0", "drive.duration"] + cols[2:]))
    for mode in ("push", "shear"):
        print(f"\n## stiffness, {mode}\n")
        print(table.markdown(rows(tabs[f"stiffness_{mode}"]), ["load.FN", "interface.kx"] + cols[2:]))


if __name__ == "__main__":
    main()
