"""Slip at the interface: how a site moves and how much of its motion a front's passage carries.  Each
measure is a function of the run (``analysis.results.Run``); no file access, no drawing.

  slip_velocity(run, x)             (t, du/dt) at the site nearest x, c_r
  peak_slip_velocity(run, x)        the largest du/dt there, c_r
  front_slip(run, i)                the slip u front i carries (the catalogue's ``slip_u``), l
  passage_slip(run, i, margin)      the slip u that happens while front i passes, l (median over its sites)
  slip_share_in_passages(run, x)    the share of a site's slip that happens while its bond is broken
  passage_frames(run)               site -> the frames every catalogued front reached it at
  rebond_frame(intact, k, s)        the first frame at or after k where site s is bonded again

Units: x and u in l, t in l/c_r, so slip velocities in c_r.
"""
from __future__ import annotations

import math

import numpy as np

from .fronts import tip_frames

MARGIN = 0.25        # l/c_r: a front's slip window starts this long before its tip arrives, ends this long
                     # after the site re-bonds


def _site(run, x: float) -> int:
    """The interface site nearest ``x`` (l)."""
    return int(np.argmin(np.abs(run.x - x)))


def slip_velocity(run, x: float) -> tuple[np.ndarray, np.ndarray]:
    """(t, du/dt) at the site nearest x: central differences of u in l over t in l/c_r, so in c_r."""
    return run.times, np.gradient(run.interface["ux"][:, _site(run, x)], run.times)


def peak_slip_velocity(run, x: float) -> float:
    """Largest u-dot (c_r) at the site nearest ``x``."""
    v = slip_velocity(run, x)[1]
    return float(v.max()) if len(v) else math.nan


def front_slip(run, front_index: int) -> float:
    """Slip u (l) one front carries: the catalogue's ``slip_u``, all the motion of each site it crosses
    between the midpoints in time to the neighbouring fronts' passages there (from t = 0 for the first
    front).  For the record's last front the window runs to the end of the record, so that front is not
    used (NaN): its slip would grow with the run's length."""
    fr = run.fronts()
    return float(fr[front_index].slip_u) if front_index + 1 < len(fr) else math.nan


def rebond_frame(intact: np.ndarray, k: int, s: int) -> int:
    """First frame at or after k where site s is intact (the last frame if it never re-bonds)."""
    on = np.flatnonzero(intact[k:, s] == 1)
    return k + int(on[0]) if len(on) else intact.shape[0] - 1


def passage_frames(run) -> dict:
    """site -> sorted arrival frames of every catalogued front there."""
    out: dict[int, list[int]] = {}
    for f in run.fronts():
        for xx, k in zip(f.tip["x"], tip_frames(run, f)):
            out.setdefault(_site(run, xx), []).append(k)
    return {s: sorted(v) for s, v in out.items()}


def passage_slip(run, front_index: int, margin: float = MARGIN) -> float:
    """Slip u (l) that happens while a front passes: at each site it crosses, u from ``margin`` before its
    tip arrives to ``margin`` after the site re-bonds (the window clipped at the midpoints to the
    neighbouring fronts' passages there); the median over the sites.  The jump a front makes, without
    the creep of the bonded interface between fronts."""
    fr, t = run.fronts(), run.times
    if len(fr) <= front_index or "ux" not in run.interface or len(t) < 2:
        return math.nan
    f = fr[front_index]
    intact, ux = run.interface["intact"], run.interface["ux"]
    m = int(round(margin / float(np.median(np.diff(t)))))
    passes = passage_frames(run)
    jumps = []
    for xx, k in zip(f.tip["x"], tip_frames(run, f)):
        s = _site(run, xx)
        ks = passes.get(s, [k])
        i = ks.index(k) if k in ks else int(np.argmin(np.abs(np.array(ks) - k)))
        k_lo = 0 if i == 0 else (ks[i - 1] + k) // 2
        k_hi = len(t) - 1 if i == len(ks) - 1 else (k + ks[i + 1]) // 2
        jumps.append(ux[min(k_hi, rebond_frame(intact, k, s) + m), s] - ux[max(k_lo, k - m), s])
    return float(np.median(jumps)) if jumps else math.nan


def slip_share_in_passages(run, x: float = 0.5, margin: float = 1.0) -> float:
    """Share of the slip u at the site nearest ``x`` that happens while its bond is broken, give or take
    ``margin`` l/c_r (between pulses the interface does not slip)."""
    s, t = _site(run, x), run.times
    if len(t) < 2:
        return math.nan
    u = run.interface["ux"][:, s]
    total = u[-1] - u[0]
    if total <= 0:
        return math.nan
    m = int(round(margin / float(np.median(np.diff(t)))))
    broken = (run.interface["intact"][:, s] == 0).astype(int)
    near = np.convolve(broken, np.ones(2 * m + 1, int), mode="same") > 0
    return float(np.diff(u)[near[1:]].sum() / total)
