"""The cohesive zone behind a slip-weakening front's tip: its width X_c at an instant, and the near-tip field
fitted ahead of it.

A bond of ``interface.softening`` D_c > 0 carries its peak traction tau_p when its weakening starts, and breaks
when its traction has fallen to the residual tau_r (docs/model/index.md).  Behind a running tip the sites
between those two events are the weakening (cohesive) zone.  From a run's interface record, along the path of a
catalogued front (whose arrivals are the breaks: the sites reaching the residual):

  t_break   each site's break, the catalogue's arrival ``front.tip["t"]`` (exact to dt, from the events)
  t_peak    the time each site's shear traction peaked (``peak_times``): near the frame of its largest
            traction (signed along the prestress) before its break, where the lines through the two frames on
            either side meet (the law's traction has a corner at its peak)

Each is a path along the front, x(t) by linear interpolation of its arrival times (``path_at``): the head
x_h(t), the most advanced point past its peak, and the tail x_t(t), the most advanced at residual.  The
zone's width at time t is a width at one instant,

    X_c(t) = d (x_h(t) - x_t(t)) l       (a; d = +1 or -1 the front's direction, x in l),

not a duration turned into a length by a speed: an accelerating front (whose zone's two ends run at
different speeds) is measured as it is.  Its resolution: a site (a) where the paths' arrivals are linearly
interpolated, and the peak time's, a fraction of ``output.interface_dt`` times the head's speed.
``zone_width`` gives it at the tail's arrivals.

``zone_field`` is route 2 of ``analysis.cracks`` (the mode II singular field fitted to the shear traction
ahead of the tip, ``mode2_fit``, turned into G by the Born continuum's velocity function, ``field_g``) at
each interface frame, with the tip's local speed at that frame rather than a stretch's one speed, the window
[w0, w1] (a) counted ahead of the zone's head, and the field's origin at the zone's tail, centre or head (the
equivalent crack's tip lies inside the zone; the three bracket what that choice moves).

Units: x in l, t in l/c_r, tractions in rho c_r^2, widths and windows in a, G in m c_r^2 / a.
"""
from __future__ import annotations

import math

import numpy as np

from ..model.physics import DENSITY
from .cracks import _material, field_g, mode2_fit, subshear, tip_speed_at

# Where route 2's field is centred, as a share of the zone from its tail (0) to its head (1).
ORIGINS = {"tail": 0.0, "centre": 0.5, "head": 1.0}


def peak_times(times, sxy, before, sign: float = 1.0) -> np.ndarray:
    """Per site, the time its traction sign * sxy peaked over the frames before ``before`` (that site's break,
    l/c_r; NaN: every frame).  The law's traction has a corner at its peak (it rises with the slip and falls
    linearly with it past the peak), so the peak is placed where the line through the two frames before the
    largest one meets the line through the two after it: exact for a traction linear in time on each side, and
    the largest frame's own time where that meeting lies outside the frames next to it or the record is too
    short.  times (nf,), sxy (nf, ns), before (ns,); returns (ns,) in l/c_r, NaN for a site without a frame
    before its break or whose largest frame is the record's last, unbroken then."""
    t = np.asarray(times, float)
    s = sign * np.asarray(sxy, float)
    b = np.asarray(before, float)
    ok = np.isnan(b)[None, :] | (t[:, None] < b[None, :])
    s = np.where(ok, s, -np.inf)
    k = np.argmax(s, axis=0)
    cols = np.arange(s.shape[1])
    # a site whose largest frame is the record's last, unbroken by then, may not have peaked yet
    unfinished = (k == len(t) - 1) & ~(b <= t[-1])
    out = np.where(ok.any(axis=0) & ~unfinished, t[k], math.nan)
    at = [np.clip(k + j, 0, len(t) - 1) for j in (-2, -1, 1, 2)]
    with np.errstate(invalid="ignore", divide="ignore"):
        cross = _meeting(*(t[i] for i in at), *(s[i, cols] for i in at))
    good = (k >= 2) & (k <= len(t) - 3) & np.isfinite(cross) & (cross >= t[at[1]]) & (cross <= t[at[2]])
    return np.where(good, cross, out)


def _meeting(t0, t1, t2, t3, y0, y1, y2, y3):
    """The time at which the line through (t0, y0), (t1, y1) meets the line through (t2, y2), (t3, y3)."""
    a, b = (y1 - y0) / (t1 - t0), (y3 - y2) / (t3 - t2)
    return (y2 - y0 + a * t0 - b * t2) / (a - b)


def path_at(x, t_arrive, t) -> np.ndarray:
    """The position (x's unit) at times t of a path that reached the points x (in the order it reached them) at
    t_arrive: linear interpolation in time, the arrivals made non-decreasing first (a site reached out of turn
    counts as reached with the next); NaN before the first arrival and after the last.  A site without an
    arrival (NaN) is left out."""
    x, ta = np.asarray(x, float), np.asarray(t_arrive, float)
    ok = np.isfinite(ta)
    x, ta = x[ok], np.maximum.accumulate(ta[ok])
    t = np.asarray(t, float)
    if len(ta) < 2:
        return np.full(t.shape, math.nan)
    inside = (t >= ta[0]) & (t <= ta[-1])
    return np.where(inside, np.interp(t, ta, x), math.nan)


def zone_width(x, t_peak, t_break, direction: int, length: float, at=None) -> np.ndarray:
    """X_c(t) = d (x_h(t) - x_t(t)) ``length`` at times ``at`` (default the breaks t_break): x (l) the front's
    sites in the order its tip reached them, t_peak and t_break their peak and break times (l/c_r), d the
    front's direction, ``length`` a in the unit of x (l / a).  NaN where the head's path does not cover t."""
    at = np.asarray(t_break if at is None else at, float)
    head, tail = path_at(x, t_peak, at), path_at(x, t_break, at)
    return direction * (head - tail) * length


def front_zone(run, front) -> dict:
    """The cohesive zone along a catalogued front of ``run`` (``analysis.results.Run``): per site of its path,
    "x" (l), "t_break", "t_peak" (l/c_r), "v" (the tip's local speed at the break, c_r, unsigned) and
    "X_c" (a, ``zone_width`` at the break), "tau_reached" (the largest traction of its frames before its break,
    rho c_r^2: the peak it reached, to a frame), and "sign", the sign of the traction the zone carries."""
    x = np.asarray(front.tip["x"], float)
    tb = np.asarray(front.tip["t"], float)
    n = len(run.x)
    sites = np.clip(np.rint(x * n - 0.5).astype(int), 0, n - 1)
    t = np.asarray(run.times, float)
    span = (t >= np.nanmin(tb) - 0.05 * (np.nanmax(tb) - np.nanmin(tb)) - 5 * _frame(t)) & (t <= np.nanmax(tb))
    sxy = np.asarray(run.interface["sxy"][np.flatnonzero(span)][:, sites], float)
    sign = 1.0 if np.nanmedian(sxy[0]) >= 0 else -1.0
    tp = peak_times(t[span], sxy, tb, sign)
    before = t[span][:, None] < tb[None, :]
    reached = np.where(before.any(axis=0), np.where(before, sign * sxy, -np.inf).max(axis=0), math.nan)
    l = float(run.attrs["l"])
    return {"x": x, "sites": sites, "t_break": tb, "t_peak": tp, "sign": sign, "tau_reached": reached,
            "v": np.abs(tip_speed_at(front, tb)), "X_c": zone_width(x, tp, tb, front.direction, l)}


def block_solid(run):
    """The block's Born continuum (``lefm.Solid.of`` of the run's material): what ``lefm``'s formulas take."""
    from .lefm import Solid
    return Solid.of(_material(run))


def _frame(t) -> float:
    return float(np.median(np.diff(t))) if len(t) > 1 else 0.0


def zone_field(run, front, zone: dict, window: tuple, origin: str = "centre") -> dict:
    """Route 2 (``mode2_fit``, ``field_g``) at every interface frame while the front's zone is whole on its
    path (both paths cover the frame): tau = tau_0 + K_II / sqrt(2 pi xi) fitted over the sites
    window[0] <= d (x - x_h) l <= window[1] (a) ahead of the head, xi = d (x - x_o) l from the origin
    x_o = x_t + f (x_h - x_t) (``ORIGINS[origin]``), G at the tip's local speed at that frame
    (``tip_speed_at``).  {"t", "v" (c_r), "K_II", "tau_0", "G" (m c_r^2 / a)}, one entry per frame; NaN where
    the window leaves the contact or the speed is not below c_s."""
    f = ORIGINS[origin]
    m, c_r, l = _material(run), float(run.attrs["c_r"]), float(run.attrs["l"])
    x, t = np.asarray(run.x, float), np.asarray(run.times, float)
    head, tail = path_at(zone["x"], zone["t_peak"], t), path_at(zone["x"], zone["t_break"], t)
    ks = np.flatnonzero(np.isfinite(head) & np.isfinite(tail))
    d = front.direction
    ahead = d * (x[None, :] - head[ks, None]) * l
    xi = d * (x[None, :] - (tail[ks] + f * (head[ks] - tail[ks]))[:, None]) * l
    sel = (ahead >= window[0]) & (ahead <= window[1])
    whole = np.count_nonzero(sel, axis=1) >= int(window[1] - window[0])
    sxy = zone["sign"] * np.asarray(run.interface["sxy"][ks], float)
    K, tau0 = mode2_fit(np.where(sel, xi, np.nan), np.where(sel, sxy, np.nan))
    v = np.abs(tip_speed_at(front, t[ks]))
    G = np.array([field_g(k * DENSITY * c_r * c_r, vv * c_r, m.kn_top, m.kt_top) / c_r ** 2
                  if ok and np.isfinite(k) and subshear(vv * c_r, m.kn_top, m.kt_top) else math.nan
                  for k, vv, ok in zip(np.atleast_1d(K), v, whole)])
    return {"t": t[ks], "v": v, "K_II": np.atleast_1d(K), "tau_0": np.atleast_1d(tau0), "G": G}
