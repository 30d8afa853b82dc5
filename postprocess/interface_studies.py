"""The interface studies' tables and figures (docs/studies/interfaces.md), from their sweeps' outputs.

    for s in precursors barriers supershear damping heal_time heal_speed; do
        mpiexec -n 2 parslip sweep run/studies/interface_$s.toml -o out/interfaces/interface_$s
    done
    python postprocess/interface_studies.py --dir out/interfaces -o docs/studies/img --tables docs/studies

(``bash postprocess/docs_numbers.sh interfaces`` runs both.)  Each table, interfaces_<study>.csv, has a row
per point with the swept keys, the measures (``parslip.analysis.rupture``, ``analysis.friction``) and the
point's resolved scene and commit; the Markdown tables the page quotes are printed.  Speeds are classed by
the package's bands (``fronts.BANDS``: a front's ``band``, the path's ``stretches``), S is the front field
``andrews_s`` and a front's end its ``fate`` (``analysis.friction``): this script only tabulates them.
"""
import argparse
import math
import os

import numpy as np

from parslip.analysis import rupture, table
from parslip.plot.figures import pyplot, save
from parslip.analysis.friction import first_crossing, reformations, slip_events
from parslip.analysis.fronts import BANDS, wave_speeds
from parslip.analysis.results import Run


STUDIES = ["precursors", "barriers", "supershear", "damping", "heal_time", "heal_speed"]


def points(d: str, study: str):
    """(summary row, run) of each point of the sweep in d/interface_<study>."""
    base = os.path.join(d, f"interface_{study}")
    tab = table.read(os.path.join(base, "summary.csv"))
    for i in range(len(tab["point"])):
        row = {k: tab[k][i] for k in tab}
        yield row, Run(os.path.join(base, row["out"]))


def write(rows, cols, path):
    """interfaces_<study>.csv with the columns ``cols`` then scene and commit; returns the Markdown table of
    ``cols`` the page quotes."""
    table.write_csv(path, cols + ["scene", "commit"], rows)
    return table.markdown(rows, cols)


def patch_of(run):
    p = run.scene.get("interface.patch") or []
    return (p[-1]["x"][0], p[-1]["x"][1], p[-1].get("delta_b", math.nan)) if p else (math.nan, math.nan, math.nan)


def precursors_study(d):
    rows, pts = [], []
    for row, run in points(d, "precursors"):
        ev = slip_events(run)
        pre_all = run.precursors()
        t, mu = run.interface["t"], run.interface["mu"]
        pre = [(p.arrest_length, float(mu[min(int(np.searchsorted(t, p.arrest_time)), len(t) - 1)]))
               for p in pre_all]
        rows.append({"point": row["point"], "load.FN": row["load.FN"], "drive.rows": row["drive.rows"] or "all",
                     "mu_s": row["mu_s"], "first_break_time": row["first_break_time"], "slip_events": len(ev),
                     "first_slip_mu_before": ev[0].mu_before if ev else math.nan,
                     "n_fronts": row["n_fronts"], "n_precursors": len(pre_all),
                     "precursor_arrest_l": "; ".join(f"{L:.3g}@{m:.3g}" for L, m in pre) or "-",
                     "scene": row["scene"], "commit": row["commit"]})
        pts.append((row, pre))
    return rows, pts


def barriers_study(d):
    rows = []
    for row, run in points(d, "barriers"):
        lo, hi, db = patch_of(run)
        fr = run.fronts()
        f = fr[0] if fr else None
        res = rupture.through_patch(f, lo, hi, c_l=wave_speeds(run)["c_max"]) if f is not None and math.isfinite(lo) \
            else {"before": math.nan, "inside": math.nan, "after": math.nan, "through": True, "bursts": 0}
        beyond = [x for x in rupture.daughters(run) if math.isfinite(hi) and x["mother"] == 0 and x["x"] >= hi]
        rows.append({"point": row["point"], "drive.mode": row["drive.mode"],
                     "patch delta_b": db if math.isfinite(db) else 0.7,
                     "first front kind": f.kind if f else "-", "first band": (f.band or "-") if f else "-",
                     "v before": res["before"], "v inside": res["inside"],
                     "v after": res["after"], "bursts": res["bursts"], "through": res["through"], "fate": run.fates()[0] if fr else "-",
                     "born beyond": len(beyond), "n_fronts": len(fr), "mu_s": row["mu_s"],
                     "scene": row["scene"], "commit": row["commit"]})
    return rows


# The supershear table's column for each speed band (``fronts.BANDS``): the share of a run's fitted sites in it.
BAND_COLS = {"sub-Rayleigh": "% sub-R", "c_R to c_s": "% c_R-c_s", "supershear": "% supershear",
             "above block c_l": "% above c_l", "burst": "% burst"}
assert set(BAND_COLS) == {name for name, _ in BANDS}


def band_shares(fronts) -> dict:
    """The share (%) of the sites of every front's path, over the run, in each speed band (``Front.stretches``:
    the path cut into bands by each site's fitted local speed), and the number of such sites."""
    n = {b: 0 for b in BAND_COLS}
    for f in fronts:
        for st in f.stretches:
            n[st["band"]] += st["n_sites"]
    total = sum(n.values())
    out = {col: 100.0 * n[b] / total if total else math.nan for b, col in BAND_COLS.items()}
    out["band sites"] = total
    return out


def supershear_study(d, study="supershear"):
    rows = []
    for row, run in points(d, study):
        fr = run.fronts()
        moved = [f for f in fr if math.isfinite(f.max_speed)]
        fastest = max(moved, key=lambda f: abs(f.max_speed)) if moved else None
        lo, hi, db = patch_of(run)
        waves = wave_speeds(run)
        sc = run.scene
        rows.append({"point": row["point"], "top_rows": sc["lattice.top_rows"], "damping": sc["time.damping"],
                     "weak band": "0.55 at 0.2-0.5" if math.isfinite(db) else "-",
                     "delta_b": sc["interface.delta_b"], "kx": sc["interface.kx"],
                     "first mean v": abs(fr[0].mean_speed) if fr else math.nan, "max v": abs(fastest.max_speed) if fastest else math.nan,
                     "max band": fastest.band if fastest else "-", **band_shares(fr),
                     "supershear fronts": sum(1 for f in fr if f.supershear),
                     "daughters": len(rupture.daughters(run)), "S": fr[0].andrews_s if fr else math.nan,
                     "n_fronts": len(fr), "scene": row["scene"], "commit": row["commit"]})
    return rows, waves


def heal_study(d, study):
    rows = []
    for row, run in points(d, study):
        fr = run.fronts()
        f = first_crossing(run, fr)
        key = "interface.heal_time" if study == "heal_time" else "interface.heal_speed"
        r = {"point": row["point"], key: row[key]}
        if study == "heal_time":
            r["drive.mode"] = row["drive.mode"]
        else:
            r["drive.v0"] = row["drive.v0"]
        v = abs(f.mean_speed) if f else math.nan
        r.update({"kind": f.kind if f else "-", "mean v": v,
                  "width a": f.width if f else math.nan, "re-formed before crossing": reformations(run, f.nucleation_time, f.t_end) if f else -1,
                  "n_fronts": len(fr), "n_crossed": row["n_crossed"], "mu_s": row["mu_s"],
                  "scene": row["scene"], "commit": row["commit"]})
        rows.append(r)
    return rows


def precursor_figure(pts, out, source):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    n = 0
    for row, pre in pts:
        if pre:
            n += len(pre)
            ax.plot([m for _, m in pre], [L for L, _ in pre], "o", label=f"F_N = {row['load.FN']:g}, rows "
                    f"{row['drive.rows'] or 'all'}")
    if not n:
        ax.text(0.5, 0.5, "no precursor in any run:\nno front arrested inside the contact", ha="center",
                va="center", transform=ax.transAxes)
    ax.set_xlabel("F_T / F_N at the arrest")
    ax.set_ylabel("arrest length / l")
    if n:
        ax.legend(fontsize=7)
    ax.set_title("precursors of the push through a soft loader", fontsize=8)
    return save(fig, out, "interfaces_precursors", source)


def supershear_figure(rows, waves, out, source):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for tr, m in ((10, "o"), (40, "s")):
        for band, c in (("-", "tab:blue"), ("0.55 at 0.2-0.5", "tab:red")):
            sel = [r for r in rows if r["top_rows"] == tr and r["weak band"] == band]
            ax.plot([r["kx"] * (1 + 0.04 * (r["delta_b"] == 0.7)) for r in sel], [r["max v"] for r in sel], m,
                    color=c, mfc="none" if tr == 40 else c, label=f"{tr} rows, weak band {band}")
    # The ends of the speed bands (fronts.BANDS): the lattice's Rayleigh speed, the block's c_s and c_l, and
    # the substrate's c_l, the fastest wave carried (a fit above it is a burst).
    for key, name, ls, at in (("c_R", "c_R", "-.", 0.93), ("c_s", "c_s", "--", 1.03), ("c_l", "block c_l", ":", 1.03),
                              ("c_max", "substrate c_l", "-", 1.03)):
        ax.axhline(waves[key], color="0.4", ls=ls, lw=0.8)
        ax.text(0.051, waves[key] * at, f"{name} = {waves[key]:.3g}", fontsize=7)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("k_x (delta_b = 0.7 drawn 4 % right of 0.6)")
    ax.set_ylabel("largest local front speed / c_r")
    ax.legend(fontsize=6, loc="center right")
    ax.set_title("T0 on weakened interfaces: the fastest fitted speed of each run, bursts included", fontsize=8)
    return save(fig, out, "interfaces_supershear", source)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dir", required=True, help="directory holding the sweeps' OUTDIRs (interface_<study>)")
    p.add_argument("-o", "--out", required=True, help="directory for the figures")
    p.add_argument("--tables", required=True, help="directory for interfaces_<study>.csv")
    p.add_argument("--only", nargs="+", choices=STUDIES, default=STUDIES,
                   help="the studies to tabulate (default all): the others' tables and figures are left as they are")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    os.makedirs(a.tables, exist_ok=True)

    def source(rows):
        return {"scene": [r["scene"] for r in rows], "commit": [r["commit"] for r in rows]}

    if "precursors" in a.only:
        rows, pts = precursors_study(a.dir)
        print("## precursors\n")
        print(write(rows, ["point", "load.FN", "drive.rows", "mu_s", "first_break_time", "slip_events",
                           "first_slip_mu_before", "n_fronts", "n_precursors", "precursor_arrest_l"],
                    os.path.join(a.tables, "interfaces_precursors.csv")))
        precursor_figure(pts, a.out, source(rows))
    if "barriers" in a.only:
        rows = barriers_study(a.dir)
        print("\n## barriers\n")
        print(write(rows, ["point", "drive.mode", "patch delta_b", "first front kind", "first band", "v before",
                           "v inside", "v after", "bursts", "through", "fate", "born beyond", "n_fronts", "mu_s"],
                    os.path.join(a.tables, "interfaces_barriers.csv")))
    for study in ("supershear", "damping"):
        if study not in a.only:
            continue
        rows, waves = supershear_study(a.dir, study)
        print(f"\n## {study}\n")
        print(f"(wave speeds, c_r: {', '.join(f'{k} = {v:.4g}' for k, v in waves.items())})\n")
        print(write(rows, ["point", "top_rows", *(["damping"] if study == "damping" else []), "weak band", "delta_b",
                           "kx", "first mean v", "max v", "max band", *BAND_COLS.values(), "band sites",
                           "supershear fronts", "daughters", "S", "n_fronts"],
                    os.path.join(a.tables, f"interfaces_{study}.csv")))
        if study == "supershear":
            supershear_figure(rows, waves, a.out, source(rows))
    for study, key, extra in (("heal_time", "interface.heal_time", "drive.mode"),
                              ("heal_speed", "interface.heal_speed", "drive.v0")):
        if study not in a.only:
            continue
        rows = heal_study(a.dir, study)
        print(f"\n## {study}\n")
        print(write(rows, ["point", extra, key, "kind", "mean v", "width a", "re-formed before crossing",
                           "n_fronts", "n_crossed", "mu_s"], os.path.join(a.tables, f"interfaces_{study}.csv")))
    for f in os.listdir(a.out):
        if f.startswith("interfaces_") and f.endswith(".pdf"):
            os.remove(os.path.join(a.out, f))


if __name__ == "__main__":
    main()
