"""The paper's figure set for one run (Sec. 3 and the appendices), with matplotlib (Agg).

Responsible for drawing the figures from a ``parslip.open`` result (and,
beyond the paper, mu(t) with the front events: ``fig_friction``) and for
the two small computations only they need: the interface-stress profile
ahead of a tip and the Mode II square-root fit (appendix B).  Every figure is
written as PNG and PDF; ``write_all`` writes the whole set for one run and
``compare_speeds`` overlays front speeds of several runs (Fig. 2d, appendix D).

Units as in the output: x, x_tip and displacements in l, t in l/c_r, speeds
in c_r, interface stresses in rho c_r^2, pulse width in lattice spacings a.
The colours of the first four fronts are the paper's: blue, orange, green, brown.
"""
from __future__ import annotations

import importlib
import importlib.util
import logging
import math
import os

import numpy as np

from ..analysis.cracks import mode2_fit_shifted

log = logging.getLogger("parslip")

YELLOW = "#f2c300"
FRONT_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:brown")
SLIP_POINTS = (0.0, 0.35, 0.98)           # x/l of the slip records (Fig. 10, appendix C)


def pyplot():
    """matplotlib.pyplot on the Agg backend (no window), except in a Jupyter kernel with its inline backend,
    where figures then show below the cell that draws them."""
    import sys

    import matplotlib
    if not ("ipykernel" in sys.modules and "inline" in os.environ.get("MPLBACKEND", "")):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save(fig, out_dir: str, name: str, source=None) -> list[str]:
    """Write ``name``.png and ``name``.pdf in ``out_dir``, stamped with the scene(s) and commit of
    ``source`` (runs or a sweep table: ``plot.provenance``); close the figure; return both paths."""
    from .provenance import savefig_metadata
    plt = pyplot()
    os.makedirs(out_dir, exist_ok=True)
    paths = [os.path.join(out_dir, f"{name}.{ext}") for ext in ("png", "pdf")]
    fig.tight_layout()
    for p, ext in zip(paths, ("png", "pdf")):
        fig.savefig(p, dpi=150, metadata=savefig_metadata(ext, source))
    plt.close(fig)
    return paths


def colour(i: int) -> str:
    return FRONT_COLOURS[i] if i < len(FRONT_COLOURS) else "0.5"


def _title(run) -> str:
    return f"{os.path.basename(run.path)}: {run.mode}, v0/c_r = {run.v0:g}"


def legend(ax, size: int) -> None:
    """A legend when something is labelled (a run without fronts has nothing to list)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=size)


def _finish(fig, axes, run, out_dir: str, name: str, xlabel: str, ylabels, with_legend: bool = True) -> list[str]:
    """Label a column of axes (x label on the last), legend and run title on the first, then save."""
    axes = list(np.atleast_1d(axes))
    for ax, yl in zip(axes, ylabels):
        ax.set_ylabel(yl)
    axes[-1].set_xlabel(xlabel)
    if with_legend:
        legend(axes[0], 7)
    axes[0].set_title(_title(run), fontsize=8)
    return save(fig, out_dir, name, run)


# --- space-time and speeds ------------------------------------------------------

def draw_spacetime(ax, iface: dict) -> None:
    """Intact bonds yellow, broken white, x/l across and t c_r/l upward (Figs. 2b, 4b, 6b)."""
    from matplotlib.colors import ListedColormap
    x, t, intact = iface["x"], iface["t"], iface["intact"]
    if len(t):
        dx = (x[1] - x[0]) if len(x) > 1 else 1.0
        dt = (t[1] - t[0]) if len(t) > 1 else 1.0
        ax.imshow(intact, origin="lower", aspect="auto", interpolation="nearest",
                  cmap=ListedColormap(["white", YELLOW]), vmin=0, vmax=1,
                  extent=[x[0] - dx / 2, x[-1] + dx / 2, t[0] - dt / 2, t[-1] + dt / 2])
    ax.set_xlabel(r"$x/l$")
    ax.set_ylabel(r"$t\,c_r/l$")


def spacetime_picture(iface: dict, png: str, title: str = "") -> bool:
    """The picture ``parslip run`` writes before it returns: the space-time diagram of the interface
    bonds (intact yellow, broken white) with axes x/l and t c_r/l and a title.  False (nothing written)
    for a free block, which has no interface."""
    if len(iface["x"]) == 0:
        return False
    # A bare Figure on the Agg canvas with fixed margins: no pyplot and no tight_layout, which every run
    # would otherwise pay (about 0.1 s of the picture's 0.65 s; importing matplotlib is most of the rest).
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(5, 6))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    draw_spacetime(ax, iface)
    ax.set_title((f"{title}\n" if title else "") + "interface bonds: intact (yellow), broken (white)", fontsize=9)
    fig.subplots_adjust(left=0.14, right=0.96, bottom=0.08, top=0.91)
    fig.savefig(png, dpi=120)
    return True


def zoom_window(run, share: float = 0.1, pad: float = 0.5, after: float = 2.0):
    """(t0, t1) in l/c_r framing every front when they all fit in less than ``share`` of the record (a
    lone fast rupture, Fig. 6b, is a hairline on the whole record's time axis): from ``pad`` before the
    first nucleation to ``after`` past the last tip, where re-bonding shows.  None otherwise."""
    fr = run.fronts()
    if not fr or len(run.times) < 2:
        return None
    t0 = min(f.nucleation_time for f in fr)
    t1 = max(float(f.tip["t"][-1]) for f in fr)
    if t1 - t0 >= share * (run.times[-1] - run.times[0]):
        return None
    return max(float(run.times[0]), t0 - pad), min(float(run.times[-1]), t1 + after)


def fig_spacetime(run, out_dir: str) -> list[str]:
    """Space-time diagram with each detected front's tip drawn over it and a red arrow for its direction;
    beside it the same zoomed in time on the fronts when they fill little of the record (``zoom_window``)."""
    plt = pyplot()
    window = zoom_window(run)
    fig, axes = plt.subplots(1, 2 if window else 1, figsize=(9 if window else 5, 6), squeeze=False)
    for ax, lim in zip(axes[0], (None, window)):
        draw_spacetime(ax, run.interface)
        for i, f in enumerate(run.fronts()):
            ax.plot(f.tip["x"], f.tip["t"], color=colour(i), lw=1.2)
            if f.direction:
                j = len(f.tip["x"]) // 2
                j1 = min(j + max(2, len(f.tip["x"]) // 8), len(f.tip["x"]) - 1)
                ax.annotate("", xy=(f.tip["x"][j1], f.tip["t"][j1]), xytext=(f.tip["x"][j], f.tip["t"][j]),
                            arrowprops=dict(arrowstyle="->", color="red", lw=1.5))
        if lim:
            ax.set_ylim(*lim)
            ax.set_title(f"zoom: t c_r/l = {lim[0]:.1f} to {lim[1]:.1f}", fontsize=8)
    axes[0, 0].set_title(_title(run) + "\nintact yellow, broken white; detected tips", fontsize=8)
    return save(fig, out_dir, "spacetime", run)


def fig_front_speed(run, out_dir: str, n: int = 4) -> list[str]:
    """Local tip speed v/c_r (signed) against x_tip/l for the first ``n`` fronts (Figs. 2c, 4c, 6c)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for i, f in enumerate(run.fronts()[:n]):
        ax.plot(f.tip["x"], f.tip["v"], color=colour(i), label=f"{i + 1}: {f.kind}, mean {f.mean_speed:.3g}")
    ax.set_xlim(0, 1)
    return _finish(fig, ax, run, out_dir, "front_speed", "x_tip / l", ("v / c_r",))


# --- interface stresses ---------------------------------------------------------

def leading_tip(fronts: list, t: float):
    """(front, x_tip) of the leading front at time ``t``: the earliest-nucleated one alive then."""
    alive = [f for f in fronts if f.nucleation_time <= t <= f.tip["t"][-1] + 1e-12]
    if not alive:
        return None, math.nan
    f = min(alive, key=lambda fr: fr.nucleation_time)
    return f, f.tip_at(t)


def stress_times(run, n: int = 4) -> list[float]:
    """Times for the interface-stress profiles: the first ``n`` nucleations when the run has a train of
    fronts (Figs. 3b, 5b); ``n`` moments along the first front's run when it has one (Fig. 7b)."""
    fr = run.fronts()
    if not fr:
        return []
    if len(fr) == 1:
        tt = fr[0].tip["t"]
        return [float(tt[int(round(q * (len(tt) - 1)))]) for q in np.linspace(0, 1, n)]
    return [f.nucleation_time for f in fr[:n]]


def fig_interface_stress(run, out_dir: str, times: list[float] | None = None) -> list[str]:
    """sigma_xy and sigma_yy along the interface against x - x_tip^1 (the leading tip) at ``times``
    (Figs. 3b-c, 5b-c, 7b-c); dashed lines mark the other fronts' tips at the first of them."""
    plt = pyplot()
    it, fr = run.interface, run.fronts()
    times = stress_times(run) if times is None else times
    fig, axes = plt.subplots(2, 1, figsize=(6, 5), sharex=True)
    for i, t in enumerate(times):
        k = run.frame_at(t)
        _, x1 = leading_tip(fr, run.times[k])
        if not math.isfinite(x1):
            x1 = 0.0
        for ax, name in zip(axes, ("sxy", "syy")):
            ax.plot(run.x - x1, it[name][k], color=colour(i), lw=1, label=f"t c_r/l = {run.times[k]:.1f}")
            for f in fr:
                if f.nucleation_time <= run.times[k] <= f.tip["t"][-1]:
                    ax.axvline(f.tip_at(run.times[k]) - x1, color=colour(i), ls="--", lw=0.6)
    return _finish(fig, axes, run, out_dir, "interface_stress", "(x - x_tip^1) / l",
                   ("sigma_xy / rho c_r^2", "sigma_yy / rho c_r^2"))


def tip_profile(run, front, t: float, field: str = "sxy", sites: int = 8):
    """(xi, sigma) ahead of ``front``'s tip at the frame nearest ``t``: xi = direction * (x - x_tip) > 0,
    in l, over at most ``sites`` sites, stopping at the contact's edge; sigma in rho c_r^2."""
    k = run.frame_at(t)
    x_tip = front.tip_at(run.times[k])
    xi = front.direction * (run.x - x_tip)
    ahead = np.flatnonzero(xi > 1e-12)
    ahead = ahead[np.argsort(xi[ahead])][:sites]
    return xi[ahead], run.interface[field][k, ahead]


def mode2_table(run, n_fronts: int = 3) -> list[dict]:
    """Mode II fits of the first ``n_fronts`` fronts at the stress-figure times they are alive at
    (their own midpoint if none): rows of front, t, K_II, x_p, sigma_max."""
    rows = []
    fr = run.fronts()
    for i, f in enumerate(fr[:n_fronts]):
        ts = [t for t in stress_times(run) if f.nucleation_time < t <= f.tip["t"][-1]]
        if not ts:
            ts = [float(f.tip["t"][len(f.tip["t"]) // 2])]
        for t in ts:
            xi, s = tip_profile(run, f, t)
            k2, xp = mode2_fit_shifted(xi, s)
            rows.append({"front": i + 1, "t": float(run.times[run.frame_at(t)]), "K_II": k2, "x_p": xp,
                         "sigma_max": float(s[0]) if len(s) else math.nan})
    return rows


def fig_mode2(run, out_dir: str, n_fronts: int = 3) -> tuple[list[str], list[dict]]:
    """sigma_xy ahead of the tip with the fitted K_II / sqrt(2 pi (xi + x_p)) dashed (appendix B)."""
    plt = pyplot()
    rows = mode2_table(run, n_fronts)
    fr = run.fronts()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for r in rows:
        f = fr[r["front"] - 1]
        xi, s = tip_profile(run, f, r["t"])
        c = colour(r["front"] - 1)
        ax.plot(xi, s, "o-", color=c, ms=3, lw=1, label=f"front {r['front']}, t c_r/l = {r['t']:.1f}: "
                f"K_II = {r['K_II']:.3g}, x_p = {r['x_p']:.3g}")
        if math.isfinite(r["K_II"]):
            xx = np.linspace(max(0.0, -r["x_p"]) + 1e-3 * xi.max(), xi.max(), 100)
            ax.plot(xx, r["K_II"] / np.sqrt(2 * np.pi * (xx + r["x_p"])), "--", color=c, lw=1)
    ax.set_xlabel("distance ahead of the tip / l")
    ax.set_ylabel("sigma_xy / rho c_r^2")
    legend(ax, 6)
    ax.set_title(_title(run) + "\nK_II in rho c_r^2 l^1/2, x_p in l", fontsize=8)
    paths = save(fig, out_dir, "mode2_fit", run)
    csv = os.path.join(out_dir, "mode2_fit.csv")
    with open(csv, "w") as fh:
        fh.write("front,t_l_per_cr,K_II_rho_cr2_sqrt_l,x_p_l,sigma_max_rho_cr2\n")
        for r in rows:
            fh.write(f"{r['front']},{r['t']:.6g},{r['K_II']:.6g},{r['x_p']:.6g},{r['sigma_max']:.6g}\n")
    return paths + [csv], rows


# --- slip -----------------------------------------------------------------------

def site_index(run, x: float) -> int:
    """The interface site nearest x (l)."""
    return int(np.argmin(np.abs(run.x - x)))


def passages(run, s: int) -> list[tuple[int, float]]:
    """(front index, time) at which each front's tip reached site ``s``."""
    out = []
    for i, f in enumerate(run.fronts()):
        hit = np.flatnonzero(np.isclose(f.tip["x"], run.x[s]))
        if len(hit):
            out.append((i, float(f.tip["t"][hit[0]])))
    return out


def fig_slip_records(run, out_dir: str, points=SLIP_POINTS) -> list[str]:
    """u(t) at three interface points, with a marker where each front passes (Fig. 10)."""
    plt = pyplot()
    ux = run.interface["ux"]
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for x, ls in zip(points, ("-", "--", ":")):
        s = site_index(run, x)
        ax.plot(run.times, ux[:, s], "k", ls=ls, lw=1, label=f"x/l = {run.x[s]:.2f}")
        for i, t in passages(run, s):
            ax.plot(t, ux[run.frame_at(t), s], "o", color=colour(i), ms=4)
    return _finish(fig, ax, run, out_dir, "slip_records", "t c_r / l", ("u / l",))


def slip_behind_tips(run, front_index: int):
    """(x_tip, du, dv) behind the tip of front ``front_index`` as in Sec. 3.4, in l.

    du: u of the site just behind the tip, from t = 0, minus the drive
    displacement v0 t_nuc(i-1) up to the previous front's nucleation (0 for the
    first front); dv: v of that site from t = 0 (the loaded equilibrium).
    """
    fr = run.fronts()
    f = fr[front_index]
    ref = run.v0 * fr[front_index - 1].nucleation_time if front_index > 0 else 0.0
    return f.tip["x"], f.tip["u_behind"] - ref, f.tip["v_behind"]


def fig_slip_behind_tips(run, out_dir: str, n: int = 4) -> list[str]:
    """Delta u and Delta v behind the tips of the first ``n`` fronts against x_tip (Fig. 9)."""
    plt = pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(5, 5), sharex=True)
    for i in range(min(n, len(run.fronts()))):
        x, du, dv = slip_behind_tips(run, i)
        axes[0].plot(x, du, color=colour(i), label=f"front {i + 1}")
        axes[1].plot(x, dv, color=colour(i))
    return _finish(fig, axes, run, out_dir, "slip_behind_tips", "x_tip / l", ("Delta u / l", "Delta v / l"))


def slip_velocity(run, x: float) -> tuple[np.ndarray, np.ndarray]:
    """(t, du/dt) at the site nearest x: central differences of u in l over t in l/c_r, so in c_r."""
    s = site_index(run, x)
    return run.times, np.gradient(run.interface["ux"][:, s], run.times)


def fig_slip_velocity(run, out_dir: str, points=SLIP_POINTS) -> list[str]:
    """The slip velocity u-dot at x/l = 0, 0.35 and 0.98 (appendix C)."""
    plt = pyplot()
    fig, axes = plt.subplots(len(points), 1, figsize=(5, 6), sharex=True)
    for ax, x in zip(axes, points):
        t, v = slip_velocity(run, x)
        ax.plot(t, v, color="tab:orange", lw=0.8)
        ax.set_ylabel(f"u-dot / c_r\nx/l = {x:g}", fontsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)
    return _finish(fig, axes, run, out_dir, "slip_velocity", "t c_r / l", (), with_legend=False)


def fig_pulse_width(run, out_dir: str, n: int = 4) -> list[str]:
    """Width of the broken zone behind the tip, in lattice spacings, against x_tip (appendix A)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for i, f in enumerate(run.fronts()[:n]):
        ax.plot(f.tip["x"], f.tip["w"], color=colour(i), drawstyle="steps-mid", label=f"front {i + 1} ({f.kind})")
    return _finish(fig, ax, run, out_dir, "pulse_width", "x_tip / l", ("width / a",))


# --- stress maps (rendered by parslip.plot.render when present) --------------

def map_times(run) -> list[float]:
    """Times of the stress maps (Figs. 3a, 5a, 7a, 8): the first front's nucleation, the fourth's (or
    the last one's) and where the first accelerates (or ends); for a lone front, its start, middle and end."""
    fr = run.fronts()
    if not fr:
        return [float(run.times[-1])] if len(run.times) else []
    f = fr[0]
    if len(fr) == 1:
        tt = f.tip["t"]
        return [float(tt[0]), float(tt[len(tt) // 2]), float(tt[-1])]
    t_acc = f.tip["t"][np.flatnonzero(f.tip["x"] == f.accel_x)[0]] if f.accel_x is not None else f.tip["t"][-1]
    return [f.nucleation_time, fr[min(3, len(fr) - 1)].nucleation_time, float(t_acc)]


def fig_stress_maps(run, out_dir: str, fields=("sxy", "sxx"), times=None) -> list[str]:
    """sigma_xy and sigma_xx over the lattice with the interface bonds in red, rendered off screen by
    ``parslip.plot.render.render_frame``; skipped with a logged note when that module is absent."""
    from . import render
    if importlib.util.find_spec("pyvista") is None:
        log.warning("stress maps skipped: they are drawn with pyvista, which is not installed; accepted: install "
                    "the [viz] extra (python -m pip install -e \".[viz]\")")
        return []
    if not len(run.snapshot_times):
        log.info("stress maps skipped: the run holds no snapshots (output.snapshots = 0)")
        return []
    out = []
    times = map_times(run) if times is None else times
    drawn = sorted({float(run.snapshot_times[np.argmin(np.abs(run.snapshot_times - t))]) for t in times})
    if len(drawn) < len(set(times)):
        log.info(f"stress maps: the times {', '.join(f'{t:.2f}' for t in times)} l/c_r fall on the snapshots "
                 f"{', '.join(f'{t:.2f}' for t in drawn)}: the run's snapshots are too sparse to tell them apart")
    for field in fields:
        for t in times:
            t_snap = float(run.snapshot_times[np.argmin(np.abs(run.snapshot_times - t))])   # what gets drawn
            png = os.path.join(out_dir, f"map_{field}_t{t_snap:07.2f}.png")
            if png not in out:
                render.render_frame(run, field, t, png)
                out.append(png)
    return out


# --- friction -----------------------------------------------------------------------

FATE_MARKERS = {"crossed": "o", "edge": "s", "relayed": "D", "merged": "v", "arrested": "X", "running": ">"}


def fig_friction(run, out_dir: str) -> list[str]:
    """mu(t) = -F_T/F_N with the front events marked, above the fronts' tip trajectories x_tip(t).

    Top: mu(t) (black), the drive's force over F_N (grey: it exceeds mu by the damping drag on the block),
    the first break (dotted), the slip onset (dashed; ``analysis.friction``), the static peak mu_s (star)
    and each front's nucleation on the curve, its marker telling its fate (o crossed, s left through an
    edge, D relayed, v merged with another front, X arrested: a precursor, > still running at the record's end).
    Bottom: each front's tip x/l against t, in the same colours, its arrest marked X.
    """
    if "mu" not in run.interface:
        log.info("friction figure skipped: the record holds no /interface/mu (written before parslip recorded "
                 "the friction force)")
        return []
    plt = pyplot()
    t, mu = run.times, run.mu
    fn = run.scene.get("load.FN") or float("nan")
    pk = run.static_peak
    fr = run.fronts()
    fates = run.fates()
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": (3, 2)})
    ax.plot(t, mu, color="k", lw=1, label=r"$\mu = -F_T/F_N$")
    if fn > 0:
        ax.plot(t, run.drive_force / fn, color="0.6", lw=0.7, label=r"$F_{drive}/F_N$")
    if pk.first_break_time is not None:
        for a in (ax, bx):
            a.axvline(pk.first_break_time, color="tab:red", ls=":", lw=1)
        ax.plot([], [], color="tab:red", ls=":", label=f"first break, t = {pk.first_break_time:.2f}")
    if pk.slip_onset is not None:
        for a in (ax, bx):
            a.axvline(pk.slip_onset, color="tab:purple", ls="--", lw=1)
        ax.plot([], [], color="tab:purple", ls="--", label=f"slip onset, t = {pk.slip_onset:.2f}")
    if math.isfinite(pk.mu_s):
        bound = "" if pk.window == "slip onset" else " (record: lower bound)"
        ax.plot(pk.time, pk.mu_s, "*", color="gold", mec="k", ms=13, zorder=5,
                label=f"$\\mu_s$ = {pk.mu_s:.3g} at t = {pk.time:.2f}{bound}")
    for i, (f, w) in enumerate(zip(fr, fates)):
        k = run.frame_at(f.nucleation_time)
        ax.plot(t[k], mu[k], FATE_MARKERS[w], color=colour(i), ms=6, mec="k", mew=0.5, zorder=4)
        bx.plot(f.tip["t"], f.tip["x"], color=colour(i), lw=1.2)
        bx.plot(f.nucleation_time, f.nucleation_x, FATE_MARKERS[w], color=colour(i), ms=5, mec="k", mew=0.5)
        if w == "arrested":
            bx.plot(f.t_end, f.x_far, "X", color=colour(i), ms=8, mec="k", mew=0.5)
    for w, m in FATE_MARKERS.items():
        if w in fates:
            ax.plot([], [], m, color="0.7", mec="k", mew=0.5, label=f"front nucleates ({w})")
    ax.set_ylabel(r"$\mu$")
    ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.set_title(_title(run) + f", F_N = {fn:g}", fontsize=8)
    bx.set_ylabel("x_tip / l")
    bx.set_ylim(0, 1)
    bx.set_xlabel("t c_r / l")
    return save(fig, out_dir, "friction", run)


def fig_stick_slip(run, out_dir: str) -> list[str]:
    """Stick-slip: mu(t) with each slip event (``analysis.friction.slip_events``) shaded from its peak to its
    trough, and the precursors (fronts arrested inside the contact) marked at their arrest; beside it
    each event's mu before and after against the loader's displacement, and every precursor's arrest
    length against F_T/F_N at its arrest."""
    from ..analysis.friction import MIN_DROP, mu as mu_of
    if "mu" not in run.interface:
        log.info("stick-slip figure skipped: the record holds no /interface/mu")
        return []
    plt = pyplot()
    iface = run.interface
    t, m = iface["t"], mu_of(run)
    events = run.slip_events()
    fig, (ax, bx, cx) = plt.subplots(1, 3, figsize=(13, 3.8), gridspec_kw={"width_ratios": [2.2, 1, 1]})
    ax.plot(t, m, color="k", lw=0.7)
    for e in events:
        ax.axvspan(e.t_start, e.t_end, color="tab:red", alpha=0.15, lw=0)
    ax.plot([e.t_start for e in events], [e.mu_before for e in events], "v", color="tab:red", ms=5,
            label=f"slip events ({len(events)}): drops of mu by >= {MIN_DROP:.0%} of its largest")
    pre_t = [p.arrest_time for p in run.precursors()]
    if pre_t:
        k = np.clip(np.searchsorted(t, pre_t), 0, len(t) - 1)
        ax.plot(t[k], m[k], "X", color="tab:blue", ms=6, label=f"precursor arrests ({len(pre_t)})")
    ax.set_xlabel("t c_r / l")
    ax.set_ylabel("mu = -F_T / F_N")
    legend(ax, 7)
    ax.set_title(_title(run), fontsize=8)
    bx.plot([e.loader for e in events], [e.mu_before for e in events], "v-", color="tab:red", ms=4, lw=0.6,
            label="before")
    bx.plot([e.loader for e in events], [e.mu_after for e in events], "^-", color="tab:green", ms=4, lw=0.6,
            label="after")
    bx.set_xlabel("loader displacement at the slip / l")
    bx.set_ylabel("mu")
    legend(bx, 7)
    bx.set_title("each slip event", fontsize=8)
    lengths = [x for e in events for x in e.precursor_lengths]
    ratios = [x for e in events for x in e.precursor_mu]
    if lengths:
        cx.plot(ratios, lengths, "X", color="tab:blue")
    else:
        cx.text(0.5, 0.5, "no precursor:\nno front arrested\ninside the contact", ha="center", va="center",
                transform=cx.transAxes, fontsize=8)
    cx.set_xlabel("F_T / F_N at the arrest")
    cx.set_ylabel("arrest length / l")
    cx.set_title("precursors", fontsize=8)
    return save(fig, out_dir, "stick_slip", run)


FIGURES = ("spacetime", "front_speed", "interface_stress", "stress_maps", "slip_records",
           "slip_behind_tips", "slip_velocity", "pulse_width", "mode2_fit", "friction", "stick_slip")


def write_all(run, out_dir: str, only=None) -> list[str]:
    """Write the figure set of one run into ``out_dir``; ``only`` limits it to some of FIGURES."""
    makers = {
        "spacetime": fig_spacetime, "front_speed": fig_front_speed, "interface_stress": fig_interface_stress,
        "stress_maps": fig_stress_maps, "slip_records": fig_slip_records,
        "slip_behind_tips": fig_slip_behind_tips, "slip_velocity": fig_slip_velocity,
        "pulse_width": fig_pulse_width, "mode2_fit": lambda r, d: fig_mode2(r, d)[0],
        "friction": fig_friction, "stick_slip": fig_stick_slip,
    }
    paths = []
    for name in (only or FIGURES):
        paths += makers[name](run, out_dir)
    return paths


# --- several runs ------------------------------------------------------------------

def _clip_to_steady(ax, factor: float = 4.0) -> None:
    """Limit the y axis to ``factor`` x the largest median |y| of the curves: the steady stretch, where
    v/v0 curves should coincide, stays readable beside the final acceleration to c_r (which, divided by
    a small v0, is thousands)."""
    ys = [np.abs(line.get_ydata()) for line in ax.get_lines() if len(line.get_ydata())]
    if ys:
        m = factor * max(float(np.median(y)) for y in ys)
        neg = any(np.median(line.get_ydata()) < 0 for line in ax.get_lines() if len(line.get_ydata()))
        ax.set_ylim(-m if neg else 0.0, m if not neg else 0.0)


def compare_speeds(runs: list, out_dir: str, n: int = 3, scale: str = "auto", name: str = "compare_speed"):
    """Front speed of the first ``n`` fronts of several runs, one panel per front.

    scale ``v0``: v/v0 against x_tip/l (Fig. 2d, the v0 sweep, where v is proportional to v0);
    the y axis is clipped to the steady stretch (``_clip_to_steady``);
    ``c_r``: |v|/c_r against the distance from the nucleation site (appendix D, push against pull,
    which run in opposite directions), on a log axis: on a linear one the steady stretch the appendix
    compares lies flat under the final run-up to c_r.  ``auto``: v0 when the runs' v0 differ.  Returns the paths
    and rows of (run, mode, v0, front, mean speed in c_r, mean speed / v0).
    """
    plt = pyplot()
    if scale == "auto":
        scale = "v0" if len({r.v0 for r in runs}) > 1 else "c_r"
    fig, axes = plt.subplots(1, n, figsize=(4 * n, 3.5), squeeze=False)
    styles = ("-", "--", ":", "-.")
    rows = []
    for j, run in enumerate(runs):
        fr = run.fronts()
        for i in range(n):
            ax = axes[0, i]
            if i >= len(fr):
                continue
            f = fr[i]
            lab = f"{run.mode}, v0/c_r = {run.v0:g}: mean {f.mean_speed / (run.v0 if scale == 'v0' else 1):.3g}"
            if scale == "v0":
                ax.plot(f.tip["x"], f.tip["v"] / run.v0, color=colour(i), ls=styles[j % 4], label=lab)
            else:
                ax.plot(np.abs(f.tip["x"] - f.nucleation_x), np.abs(f.tip["v"]), ls=styles[j % 4], label=lab)
            rows.append({"run": run.path, "mode": run.mode, "v0": run.v0, "front": i + 1,
                         "mean_speed": f.mean_speed, "mean_speed_over_v0": f.mean_speed / run.v0})
    for i in range(n):
        ax = axes[0, i]
        if scale == "v0":
            _clip_to_steady(ax)
        elif ax.get_lines():
            ax.set_yscale("log")            # slow pulses (~0.01 c_r) and their run-up to c_r on one axis
        ax.set_title(f"front {i + 1}", fontsize=9)
        ax.set_xlabel("x_tip / l" if scale == "v0" else "distance from the nucleation site / l")
        ax.set_ylabel("v / v0" if scale == "v0" else "|v| / c_r")
        legend(ax, 6)
    return save(fig, out_dir, name, list(runs)), rows
