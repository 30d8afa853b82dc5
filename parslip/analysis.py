"""Reading the interface record back: rupture fronts and the space-time plot.

Responsible for what the acceptance checks and the postprocess scripts
compute from ``/interface``: when and where bonds first break, each rupture
front (a connected patch of broken bonds in the x-t plane) with its
nucleation point, direction and speed, and the paper-style space-time PNG
(intact bonds yellow, broken white).  Speeds come out in units of c_r
because x is in l and t in l/c_r.
"""
from __future__ import annotations

from dataclasses import dataclass

import h5py
import numpy as np
from scipy import ndimage


def load_interface(path: str) -> dict:
    with h5py.File(path, "r") as f:
        g = f["interface"]
        n = int(g.attrs.get("frames_written", g["time"].shape[0]))
        return {"x": g["x"][...], "t": g["time"][:n], "intact": g["intact"][:n],
                "ux": g["ux"][:n], "uy": g["uy"][:n], "partner": g["partner"][:n]}


def first_break(iface: dict):
    """(t, x) of the first frame with a broken bond: time in l/c_r, the broken sites' x in l."""
    broken = iface["intact"] == 0
    rows = np.flatnonzero(broken.any(axis=1))
    if len(rows) == 0:
        return None, np.zeros(0)
    k = rows[0]
    return float(iface["t"][k]), iface["x"][broken[k]]


@dataclass
class Front:
    t_start: float      # l/c_r
    x_start: float      # l, mean x of the sites broken at nucleation
    t_end: float
    x_far: float        # l, the site reached last
    direction: int      # +1 toward x = 1 (front), -1 toward x = 0 (rear), 0 if it did not move
    speed: float        # median front speed over the middle of its run, in c_r
    sites: int          # number of sites it broke


def fronts(iface: dict, min_sites: int = 5) -> list[Front]:
    """Rupture fronts: 8-connected patches of broken bonds in the (t, x) plane.

    For each patch the arrival time t_a(x) at each site is the first frame
    the site is broken in that patch; the speed is the slope dx/dt_a fitted
    over the middle 60 % of the sites it crossed.  Patches breaking fewer
    than ``min_sites`` sites are dropped.
    """
    broken = iface["intact"] == 0
    labels, n = ndimage.label(broken, structure=np.ones((3, 3), int))
    t, x = iface["t"], iface["x"]
    out = []
    for lab in range(1, n + 1):
        m = labels == lab
        cols = np.flatnonzero(m.any(axis=0))
        if len(cols) < min_sites:
            continue
        first = np.argmax(m[:, cols], axis=0)          # first frame per site
        ta = t[first]
        k0 = first.min()
        x0 = float(x[cols[first == k0]].mean())
        order = np.argsort(ta, kind="stable")
        xs, ts = x[cols][order], ta[order]
        far = float(xs[-1])
        direction = int(np.sign(round(far - x0, 6)))
        lo, hi = int(0.2 * len(xs)), max(int(0.8 * len(xs)), int(0.2 * len(xs)) + 2)
        seg_x, seg_t = xs[lo:hi], ts[lo:hi]
        if len(seg_x) >= 2 and np.ptp(seg_t) > 0:
            speed = abs(float(np.polyfit(seg_t, seg_x, 1)[0]))
        else:
            speed = float("inf")      # crossed within one frame: faster than the cadence resolves
        out.append(Front(float(t[k0]), x0, float(t[first.max()]), far, direction, speed, len(cols)))
    out.sort(key=lambda fr: fr.t_start)
    return out


def summary(iface: dict) -> str:
    tb, xb = first_break(iface)
    lines = []
    if tb is None:
        lines.append("no bond broke")
    else:
        lines.append(f"first break at t = {tb:.3f} l/c_r, x/l = {', '.join(f'{v:.3f}' for v in xb[:6])}")
    fr = fronts(iface)
    lines.append(f"{len(fr)} rupture fronts")
    for i, f in enumerate(fr[:12]):
        d = {1: "-> front (x=1)", -1: "-> rear (x=0)", 0: "(stationary)"}[f.direction]
        lines.append(f"  #{i + 1}: nucleates t = {f.t_start:7.2f} at x/l = {f.x_start:.3f} {d}, "
                     f"reaches x/l = {f.x_far:.3f} at t = {f.t_end:7.2f}, v/c_r = {f.speed:.3g}, {f.sites} sites")
    return "\n".join(lines)


def spacetime_png(iface: dict, png: str, title: str = "") -> None:
    """Space-time plot of intact bonds (yellow) and broken ones (white), t c_r/l upward."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    x, t, intact = iface["x"], iface["t"], iface["intact"]
    fig, ax = plt.subplots(figsize=(5, 6), dpi=150)
    if len(t):
        dx = (x[1] - x[0]) if len(x) > 1 else 1.0
        ax.imshow(intact, origin="lower", aspect="auto", interpolation="nearest",
                  cmap=ListedColormap(["white", "#f2c300"]), vmin=0, vmax=1,
                  extent=[x[0] - dx / 2, x[-1] + dx / 2, t[0], t[-1]])
    ax.set_xlabel("x / l")
    ax.set_ylabel("t c_r / l")
    ax.set_title(title or "interface bonds: intact (yellow), broken (white)", fontsize=9)
    fig.tight_layout()
    fig.savefig(png)
    plt.close(fig)
