"""Where a rupture nucleated at a point turns supershear, read off its rupture-time field: the birth of the
daughter front (Andrews 1976; Burridge 1973) and the speeds the supershear front runs at as it grows.  Pure
measures of arrays, and one reader of a run (``rupture_times``); no file access, no drawing.

rupture_times(run, after)        each interface site's first break at or after ``after`` (l/c_r; NaN: none)
side(times, centre, direction)   one side of a bilateral rupture: distance r from the hypocentre (a) and
                                 rupture time since the first break (a/c_r), outward, up to its first
                                 unbroken site
daughter_birth(r, t, start)      the birth of the first daughter beyond ``start``: the first site that broke
                                 before a site nearer the hypocentre, followed to the earliest break of its
                                 cluster (where the daughter was born); None when every site broke after all
                                 nearer ones
free_start(r, t, forced, half)   where the rupture first broke a site before its forced front reached it
                                 (a; ``half``, the zone's edge, when it never did)
first_supershear(r, t, c_s, ..)  the first distance from which the front runs above c_s to its end
transition_distance(r, t, ..)    L_trans: the daughter's birth, else the first supershear distance, with how
                                 it was found and its resolution
window_speeds(r, t, since, ..)   the front's speed by straight lines over windows of sites, against r

Units: r in a (site centres), t in a/c_r, speeds in c_r.  A rupture-time field t(r) that grows with r is one
front; a daughter born ahead of the mother's tip at r_d breaks there first and grows both ways, so t(r)
falls toward r_d from the mother's side: a local minimum beyond the nucleation zone.  Its birth is resolved to
one site in r and to one time step in t (the break events are exact steps).
"""
from __future__ import annotations

import math

import numpy as np

from ..io.contract import EVENT_BREAK

# A site counts as broken ahead of the front when it broke this much (a/c_r) before a nearer site: a few time
# steps (0.42 a/c_r on the default block), so that two sites a burst breaks in the same few steps do not count.
MIN_LEAD = 1.0
# Sites over which a straight line through the arrivals must run above c_s (about a process zone at Lambda
# = 8 a; over fewer sites the arrivals' one-step jitter alone moves a tip at c_R above c_s).
MIN_SITES = 10


def rupture_times(run, after: float) -> np.ndarray:
    """Each interface site's first break (``/interface/events``, exact steps) at or after time ``after``
    (l/c_r): an array over the block's sites, NaN where the site did not break after it."""
    ev = run.interface["events"]
    brk = np.asarray(ev["kind"]) == EVENT_BREAK
    t, s = np.asarray(ev["time"], float)[brk], np.asarray(ev["site"])[brk]
    keep = t >= after
    t, s = t[keep], s[keep]
    out = np.full(int(run.scene["lattice.top_cols"]), math.nan)
    order = np.lexsort((t, s))                       # by site, earliest first
    s, t = s[order], t[order]
    first = np.ones(len(s), bool)
    first[1:] = s[1:] != s[:-1]
    out[s[first]] = t[first]
    return out


def side(times: np.ndarray, centre: float, direction: int, unit: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(r, t) of one side of a rupture from the hypocentre ``centre`` (in sites: site i has its centre at
    i + 1/2): the sites on ``direction`` (+1, -1) of it in order, r their distance (a), t their rupture time
    from the earliest of ``times`` (times in l/c_r, ``unit`` = l in a: t in a/c_r), cut at the first site
    that did not break (the front stopped there)."""
    if not np.isfinite(times).any():
        return np.array([]), np.array([])
    x = np.arange(len(times)) + 0.5
    r = (x - centre) * direction
    idx = np.flatnonzero(r > 0)
    idx = idx[np.argsort(r[idx])]
    t = (times[idx] - np.nanmin(times)) * unit
    gone = np.flatnonzero(~np.isfinite(t))
    stop = gone[0] if len(gone) else len(idx)
    return r[idx][:stop], t[:stop]


def daughter_birth(r: np.ndarray, t: np.ndarray, start: float, min_lead: float = MIN_LEAD) -> dict | None:
    """The first daughter beyond ``start`` (a): the first site j with r_j > start that broke ``min_lead``
    before some nearer site (t_j < max_{i<j} t_i - min_lead), followed outward while the times keep falling
    to the earliest break of its cluster, where the daughter was born: {"r", "t" (its birth), "lead" (how
    much earlier than the latest nearer break, a/c_r), "index"}; None when there is none."""
    latest = np.maximum.accumulate(t)
    for j in range(1, len(r)):
        if r[j] <= start or t[j] >= latest[j - 1] - min_lead:
            continue
        k = j
        while k + 1 < len(r) and t[k + 1] <= t[k]:
            k += 1
        return {"r": float(r[k]), "t": float(t[k]), "lead": float(latest[j - 1] - t[k]), "index": int(k)}
    return None


def free_start(r: np.ndarray, t: np.ndarray, forced: np.ndarray, half: float) -> float:
    """Where the rupture ran ahead of its forced nucleation (a): the first r_i < ``half`` (the zone's
    half-width) with t_i < forced_i, a site that broke before the forcing reached it (``forced``: the
    forcing's arrival at each r, on the clock of ``t``; the forcing then takes nucleation.duration to weaken a
    site, so a site broken before it arrived was broken by the rupture alone); ``half`` when none did (the
    rupture left the zone by itself only at its edge).  Beyond it the rupture runs by itself: a transition
    there is the rupture's, not the zone's."""
    ahead = np.flatnonzero((r < half) & (t < forced))
    return float(r[ahead[0]]) if len(ahead) else float(half)


def _line_speed(r: np.ndarray, t: np.ndarray) -> float:
    """The speed (a per a/c_r) of a straight line r(t) through the arrivals; NaN for simultaneous ones."""
    return float(np.polyfit(t, r, 1)[0]) if len(r) > 1 and np.ptp(t) > 0 else math.nan


def first_supershear(r: np.ndarray, t: np.ndarray, c_s: float, start: float, n: int = MIN_SITES) -> float:
    """The first r_i > ``start`` from which a line through the arrivals of the next ``n`` sites runs above
    ``c_s``, and one through every arrival from there to the front's end too; NaN when there is none."""
    for i in np.flatnonzero(r > start):
        if i + n > len(r):
            break
        if _line_speed(r[i:i + n], t[i:i + n]) > c_s and _line_speed(r[i:], t[i:]) > c_s:
            return float(r[i])
    return math.nan


def transition_distance(r: np.ndarray, t: np.ndarray, c_s: float, start: float, n: int = MIN_SITES,
                        min_lead: float = MIN_LEAD) -> dict:
    """L_trans (a) of one side beyond ``start`` (the nucleation zone's half-width): the daughter's birth
    (``daughter_birth``; resolution one site) when there is one, else where the tip itself went above c_s
    for good (``first_supershear``; resolution n/2 sites, the window's half), else NaN.  With "by" (how:
    "daughter", "tip above c_s" or None), "resolution" (a), "reach" (the farthest site the front broke, a)
    and "v_exit" (the line's speed over the first n sites beyond ``start``, c_r: a front that leaves the
    zone above c_s turned supershear inside it)."""
    beyond = np.flatnonzero(r > start)[:n]
    out = {"reach": float(r[-1]) if len(r) else math.nan,
           "v_exit": _line_speed(r[beyond], t[beyond]) if len(beyond) == n else math.nan}
    kid = daughter_birth(r, t, start, min_lead)
    if kid is not None:
        return {**out, "L_trans": kid["r"], "by": "daughter", "resolution": 1.0, "lead": kid["lead"]}
    fast = first_supershear(r, t, c_s, start, n)
    if math.isfinite(fast):
        return {**out, "L_trans": fast, "by": "tip above c_s", "resolution": 0.5 * n, "lead": math.nan}
    return {**out, "L_trans": math.nan, "by": None, "resolution": math.nan, "lead": math.nan}


def window_speeds(r: np.ndarray, t: np.ndarray, since: float, until: float, window: int = 20,
                  step: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """(r_mid, v): the front's speed (c_r) by straight lines through the arrivals of ``window`` consecutive
    sites, every ``step`` sites, over since < r <= until (a); r_mid the window's middle, the half-length
    of a bilateral crack then."""
    idx = np.flatnonzero((r > since) & (r <= until))
    mids, vs = [], []
    for a in range(0, len(idx) - window + 1, step):
        k = idx[a:a + window]
        mids.append(float(r[k].mean()))
        vs.append(_line_speed(r[k], t[k]))
    return np.asarray(mids), np.asarray(vs)
