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

import numpy as np

from ..io.contract import read_interface


def load_interface(path: str) -> dict:
    """The interface record (``io.contract.read_interface``): x, t, intact, partner, ux, uy, sxy, syy."""
    return read_interface(path)


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
    x_start: float      # l, the site where it nucleated
    t_end: float
    x_far: float        # l, the site reached last
    direction: int      # +1 toward x = 1 (front), -1 toward x = 0 (rear), 0 if it did not move
    speed: float        # median front speed over the middle of its run, in c_r
    sites: int          # number of sites it broke


def break_events(iface: dict) -> tuple[np.ndarray, np.ndarray]:
    """(frame, site) of every intact -> broken transition, in time order."""
    broken = iface["intact"] == 0
    new = broken.copy()
    new[1:] &= ~broken[:-1]
    k, s = np.nonzero(new)
    return k, s


def fronts(iface: dict, max_gap: float = 3.0, min_sites: int = 5) -> list[Front]:
    """Rupture fronts as chains of bond-break events, site to neighbouring site.

    Events are taken in time order.  An event at site i joins the chain whose
    tip (latest site) is at i-1 or i+1 and broke at most ``max_gap`` l/c_r
    earlier (the most recent such chain); a repeat break at a chain's own tip
    is absorbed; otherwise the event nucleates a new chain.  Pulses that
    follow each other are told apart because each extends only from its own
    tip.  The speed is the slope dx/dt fitted over the middle 60 % of the
    chain's sites; chains shorter than ``min_sites`` are dropped.
    """
    t, x = iface["t"], iface["x"]
    chains: list[list[tuple[float, int]]] = []
    for k, s in zip(*break_events(iface)):
        tk = t[k]
        best, best_t = None, -np.inf
        for c in chains:
            tt, ts = c[-1]
            if tk - tt <= max_gap and abs(ts - s) <= 1 and tt > best_t:
                best, best_t = c, tt
        if best is None:
            chains.append([(tk, s)])
        elif best[-1][1] != s and all(site != s for _, site in best):
            best.append((tk, s))
    out = []
    for c in chains:
        if len(c) < min_sites:
            continue
        ts = np.array([e[0] for e in c])
        xs = x[np.array([e[1] for e in c])]
        lo, hi = int(0.2 * len(xs)), max(int(0.8 * len(xs)), int(0.2 * len(xs)) + 2)
        seg_t, seg_x = ts[lo:hi], xs[lo:hi]
        speed = abs(float(np.polyfit(seg_t, seg_x, 1)[0])) if np.ptp(seg_t) > 0 else float("inf")
        out.append(Front(float(ts[0]), float(xs[0]), float(ts[-1]), float(xs[-1]),
                         int(np.sign(round(xs[-1] - xs[0], 9))), speed, len(c)))
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


def spacetime_png(iface: dict, png: str, title: str = "") -> bool:
    """Space-time plot of intact bonds (yellow) and broken ones (white), t c_r/l upward."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    x, t, intact = iface["x"], iface["t"], iface["intact"]
    if len(x) == 0:
        return False            # a free block has no interface to plot
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
    return True
