"""Measurements of the paper's quantitative statements on any run (``parslip.open`` results).

Responsible for the numbers ``studies.paper.claims`` compares with the paper:
nucleation times and sites, pulse intervals, speeds and accelerations,
widths, the slip a front carries, slip velocities, interface stresses around
a tip and the Mode II fit, re-attachment behind a fast front.  Each function
takes runs, never starts one (``studies.paper.study`` does that), and returns
NaN (or None) when the run does not hold what it needs.

Units: t in l/c_r, x and slip in l, speeds in c_r, widths in lattice
spacings a (one interface site = one a), interface stresses in rho c_r^2.
"""
from __future__ import annotations

import math

import numpy as np

from ...analysis.fronts import (MAX_GAP, MIN_SITES, accel_time, crack_speed, driven_edge, first_break_frame,
                                tip_frames)
from ...analysis.cracks import mode2_fit_shifted
from ...analysis.slip import MARGIN, front_slip, passage_frames, passage_slip, rebond_frame, slip_velocity

EDGE = 0.05          # l: a front "nucleates at the driven edge" within this distance of it
STEADY = (0.1, 0.6)  # distance from the nucleation site (l) where pulses run at their steady speed


# --- fronts at the driven edge ---------------------------------------------------------

def edge_fronts(run) -> list:
    """Fronts nucleated at the edge the run's drive loads first: x = 0 for push and shear, 1 for pull."""
    edge = driven_edge(run)
    return [f for f in run.fronts() if abs(f.nucleation_x - edge) < EDGE]


def edge_nucleations(run, min_sites: int = MIN_SITES, max_gap: float = MAX_GAP) -> list:
    """Every front nucleated at the driven edge (``edge_fronts``), counting one cut short by the end of
    the record: a front with fewer than ``min_sites`` sites counts when its tip was still advancing
    within ``max_gap`` l/c_r of the last frame (it is young, not small)."""
    edge = driven_edge(run)
    t_end = float(run.times[-1]) if len(run.times) else 0.0
    return [f for f in run.fronts(min_sites=1) if abs(f.nucleation_x - edge) < EDGE
            and (len(f.tip["x"]) >= min_sites or t_end - float(f.tip["t"][-1]) <= max_gap)]


def nucleation_times(run, n: int = 4) -> list[float]:
    return [f.nucleation_time for f in edge_fronts(run)[:n]]


def nucleation_time(run, i: int) -> float:
    """Nucleation time of the i-th (0-based) edge front, l/c_r; NaN if there is none."""
    t = nucleation_times(run, i + 1)
    return t[i] if len(t) > i else math.nan


def intervals(run) -> np.ndarray:
    """Times between successive nucleations at the driven edge, l/c_r."""
    return np.diff([f.nucleation_time for f in edge_fronts(run)])


def interval(run) -> float:
    """Mean time between successive nucleations at the driven edge, l/c_r."""
    d = intervals(run)
    return float(np.mean(d)) if len(d) else math.nan


def interval_spread(run) -> float:
    """Coefficient of variation (std / mean) of the nucleation intervals at the driven edge."""
    d = intervals(run)
    return float(np.std(d) / np.mean(d)) if len(d) > 1 else math.nan


def nucleation_site(run) -> float:
    """Median x/l of the edge fronts' nucleation sites; NaN when no front nucleated at the edge."""
    fr = edge_fronts(run)
    return float(np.median([f.nucleation_x for f in fr])) if fr else math.nan


def directions(run) -> float:
    """Share of the edge fronts that run away from the driven edge (+1 from x = 0, -1 from x = 1)."""
    fr = edge_fronts(run)
    away = -1 if run.mode == "pull" else 1
    return float(np.mean([f.direction == away for f in fr])) if fr else math.nan


def pulse_share(run) -> float:
    """Share of the edge fronts the catalogue calls pulses (bonds re-attached behind the tip)."""
    fr = edge_fronts(run)
    return float(np.mean([f.kind == "pulse" for f in fr])) if fr else math.nan


# --- speeds ------------------------------------------------------------------------------

def _stretch(front, lo: float, hi: float) -> np.ndarray:
    d = np.abs(front.tip["x"] - front.nucleation_x)
    return (d >= lo) & (d <= hi)


def steady_speed(front, lo: float = STEADY[0], hi: float = STEADY[1]) -> float:
    """Median |v|/c_r of a front while its distance from its nucleation site is within [lo, hi] l (a burst's
    sites, which carry no speed, left out)."""
    v = _speeds(np.abs(front.tip["v"][_stretch(front, lo, hi)]))
    return float(np.median(v)) if len(v) else math.nan


def _speeds(v: np.ndarray) -> np.ndarray:
    """The local speeds that are speeds: a burst's sites hold NaN (``analysis.fronts``)."""
    return v[np.isfinite(v)]


def steady_speeds(run, n: int = 4) -> list[float]:
    return [steady_speed(f) for f in edge_fronts(run)[:n]]


def mean_steady_speed(run, n: int = 3) -> float:
    """Mean of ``steady_speed`` over the first ``n`` edge fronts, c_r."""
    v = [x for x in steady_speeds(run, n) if math.isfinite(x)]
    return float(np.mean(v)) if v else math.nan


def speed_spread(run, n: int = 4) -> float:
    """max / min of the steady speeds of the first ``n`` edge fronts (all n needed)."""
    v = steady_speeds(run, n)
    if len(v) < n or not all(math.isfinite(x) and x > 0 for x in v):
        return math.nan
    return max(v) / min(v)


def speed_constancy(run, n: int = 3) -> float:
    """Median over the first ``n`` edge fronts of |v(0.35-0.6) / v(0.1-0.35) - 1|: how much a pulse's
    speed changes between the two halves of its steady stretch."""
    out = []
    for f in edge_fronts(run)[:n]:
        a, b = steady_speed(f, 0.1, 0.35), steady_speed(f, 0.35, 0.6)
        if math.isfinite(a) and math.isfinite(b) and a > 0:
            out.append(abs(b / a - 1))
    return float(np.median(out)) if out else math.nan


def accel_x(run) -> float:
    """x/l where the leading edge front starts to accelerate (``Front.accel_x``)."""
    fr = edge_fronts(run)
    return math.nan if not fr or fr[0].accel_x is None else float(fr[0].accel_x)


def leading_accel_time(run) -> float:
    fr = edge_fronts(run)
    return accel_time(fr[0]) if fr else math.nan


def max_speed_near_far_edge(run, within: float = 0.3) -> float:
    """Largest |v|/c_r of the leading edge front over its last ``within`` l before the far edge."""
    fr = edge_fronts(run)
    if not fr:
        return math.nan
    f = fr[0]
    far = 0.0 if run.mode == "pull" else 1.0
    m = np.abs(f.tip["x"] - far) <= within
    v = _speeds(np.abs(f.tip["v"][m]))
    return float(np.max(v)) if len(v) else math.nan


def _speed_in(front, t0: float, t1: float) -> float:
    m = (front.tip["t"] > t0) & (front.tip["t"] <= t1)
    v = _speeds(np.abs(front.tip["v"][m]))
    return float(np.median(v)) if len(v) else math.nan


def trailing_speedup(run, window: float = 3.0) -> float:
    """Speed of the second edge front over the ``window`` l/c_r after the leading one starts to accelerate,
    over its speed in the ``window`` before (Sec. 3.1.2: the trailing pulses accelerate with it)."""
    fr = edge_fronts(run)
    if len(fr) < 2:
        return math.nan
    ta = accel_time(fr[0])
    if not math.isfinite(ta):
        return math.nan
    before, after = _speed_in(fr[1], ta - window, ta), _speed_in(fr[1], ta, ta + window)
    return after / before if math.isfinite(before) and before > 0 and math.isfinite(after) else math.nan


def later_crack_speeds(run, fronts=(1, 2), past: float = 0.2) -> float:
    """The smallest ``crack_speed`` of fronts ``fronts`` (0-based), c_r; NaN if one is missing."""
    v = [crack_speed(run, i, past) for i in fronts]
    return min(v) if all(math.isfinite(x) for x in v) else math.nan


def live_pulses(run, t: float) -> int:
    """Edge fronts nucleated before ``t`` whose tip had not yet reached its last site (in flight)."""
    return sum(1 for f in edge_fronts(run) if f.nucleation_time < t <= float(f.tip["t"][-1]))


def in_flight_at_nucleation(run, i: int = 3) -> int:
    """Edge fronts in flight just before the i-th (0-based) edge front nucleates (the paper's 'three pulses
    ... another new pulse is about to nucleate'), so a nucleation a frame early or late does not count the
    newborn; -1 when there is no i-th front."""
    fr = edge_fronts(run)
    if len(fr) <= i:
        return -1
    return live_pulses(run, fr[i].nucleation_time - 1e-9)


def secondary_fronts(run, lo: float = 0.03, hi: float = 0.25, min_sites: int = 3) -> int:
    """Fronts (of at least ``min_sites`` sites) nucleated inside the contact at lo <= distance from the rear
    edge <= hi and running toward the driven edge (Sec. 3.2.2: T+ secondary fronts from x/l ~ 0.1)."""
    rear = 1.0 - driven_edge(run)
    toward = 1 if driven_edge(run) == 1.0 else -1
    return sum(1 for f in run.fronts(min_sites=min_sites)
               if lo <= abs(f.nucleation_x - rear) <= hi and f.direction == toward)


# --- widths ------------------------------------------------------------------------------

def steady_width(run, n: int = 4) -> float:
    """Median width (a) of the first ``n`` edge fronts over their steady stretch."""
    w = []
    for f in edge_fronts(run)[:n]:
        w += list(f.tip["w"][_stretch(f, *STEADY)])
    return float(np.median(w)) if w else math.nan


def width_variation(run, n: int = 4) -> float:
    """Median over the first ``n`` edge fronts of the range (max - min, a) of the width over the middle
    of the steady stretch (its 10th to 90th percentile, so one odd frame does not count)."""
    out = []
    for f in edge_fronts(run)[:n]:
        w = f.tip["w"][_stretch(f, *STEADY)]
        if len(w) > 2:
            out.append(float(np.percentile(w, 90) - np.percentile(w, 10)))
    return float(np.median(out)) if out else math.nan


def far_edge_widening(run, n: int = 4, near: float = 0.85) -> float:
    """Median over the first ``n`` edge fronts of (median width past ``near`` l from the nucleation site)
    minus (median width over the steady stretch), a (appendix A: pulses widen near the far edge)."""
    out = []
    for f in edge_fronts(run)[:n]:
        d = np.abs(f.tip["x"] - f.nucleation_x)
        far, mid = f.tip["w"][d >= near], f.tip["w"][_stretch(f, *STEADY)]
        if len(far) and len(mid):
            out.append(float(np.median(far) - np.median(mid)))
    return float(np.median(out)) if out else math.nan


def width_jump(run, window: float = 3.0) -> float:
    """Width change (a) of the second edge front across the leading one's acceleration: median width
    over the ``window`` l/c_r after minus before (appendix A's jumps a, b, c)."""
    fr = edge_fronts(run)
    if len(fr) < 2:
        return math.nan
    ta = accel_time(fr[0])
    f = fr[1]
    tt, w = f.tip["t"], f.tip["w"]
    before = w[(tt > ta - window) & (tt <= ta)]
    after = w[(tt > ta) & (tt <= ta + window)]
    if not math.isfinite(ta) or not len(before) or not len(after):
        return math.nan
    return float(np.median(after) - np.median(before))


# --- slip -------------------------------------------------------------------------------

def median_front_slip(run, n: int = 4, first: int = 1) -> float:
    """Median ``front_slip`` of fronts ``first`` .. ``n`` - 1 (0-based): by default the interior ones, each
    with a front before and after it, so every window is bounded on both sides."""
    s = [front_slip(run, i) for i in range(first, min(n, len(run.fronts())))]
    s = [v for v in s if math.isfinite(v)]
    return float(np.median(s)) if s else math.nan


def first_front_excess(run, n: int = 3) -> float:
    """Slip of the first front over the median slip of fronts 2..n (Sec. 3.4: the first is larger)."""
    first = front_slip(run, 0)
    rest = median_front_slip(run, n, 1)
    return first / rest if math.isfinite(first) and math.isfinite(rest) and rest > 0 else math.nan


def slip_spread(run, fronts=range(1, 6)) -> float:
    """Coefficient of variation of ``front_slip`` over the given fronts (constant slip per pulse)."""
    s = [front_slip(run, i) for i in fronts if i < len(run.fronts())]
    s = [v for v in s if math.isfinite(v)]
    return float(np.std(s) / np.mean(s)) if len(s) > 1 and np.mean(s) > 0 else math.nan


def net_vertical_over_slip(run, n: int = 4) -> float:
    """|median slip_v| / median slip_u of the first ``n`` fronts: the vertical displacement a pulse leaves
    behind, relative to the slip it carries."""
    fr = run.fronts()[:n]
    if not fr:
        return math.nan
    u = float(np.median([f.slip_u for f in fr]))
    v = float(np.median([f.slip_v for f in fr]))
    return abs(v) / abs(u) if u else math.nan


def lift_at_nucleation(run, within: float = 0.05) -> float:
    """Median Delta v (l) of the site behind the first edge front's tip while the tip is within ``within`` l
    of its nucleation site (Sec. 3.4: Delta v > 0 at the nucleation edge, the interface detaches)."""
    fr = edge_fronts(run)
    if not fr:
        return math.nan
    f = fr[0]
    m = np.abs(f.tip["x"] - f.nucleation_x) <= within
    v = f.tip["v_behind"][m]
    v = v[np.isfinite(v)]
    return float(np.median(v)) if len(v) else math.nan


def passage_contrast(run, x: float = 0.35, margin: float = 0.5) -> float:
    """Mean slip velocity at the site nearest ``x`` while its bond is broken (give or take ``margin``)
    over the mean outside those times (appendix C: u-dot rises as a pulse arrives, falls as it leaves)."""
    s = int(np.argmin(np.abs(run.x - x)))
    t, v = slip_velocity(run, x)
    if len(t) < 3:
        return math.nan
    m = int(round(margin / float(np.median(np.diff(t)))))
    broken = run.interface["intact"][:, s] == 0
    near = np.convolve(broken.astype(int), np.ones(2 * m + 1, int), mode="same") > 0
    if not near.any() or near.all():
        return math.nan
    out = abs(float(np.mean(v[~near])))
    return float(np.mean(v[near])) / out if out > 0 else math.inf


def stationary_before_arrival(run, x: float = 0.98) -> float:
    """u gained at the site nearest ``x`` before the first front reaches it, over the jump that front then
    makes (``passage_slip``): near 0 when the site stays put until then."""
    s = int(np.argmin(np.abs(run.x - x)))
    passes = passage_frames(run).get(s)
    if not passes:
        return math.nan
    ux = run.interface["ux"][:, s]
    k = max(passes[0] - 1, 0)                       # the last frame before the tip arrives
    slip = passage_slip(run, 0)                     # the jump the first front then makes
    return float((ux[k] - ux[0]) / slip) if slip and math.isfinite(slip) else math.nan


def sharp_peaks(run, points=(0.0, 0.35, 0.98), factor: float = 20.0) -> float:
    """Smallest, over the ``points``, of peak u-dot over the median |u-dot| of the record (a crack's sharp
    slip-velocity peak at each location, appendix C)."""
    out = []
    for x in points:
        _, v = slip_velocity(run, x)
        med = float(np.median(np.abs(v)))
        out.append(float(np.max(v)) / med if med > 0 else math.inf)
    return min(out) if out else math.nan


def same_slip_everywhere(run, points=(0.0, 0.35, 0.98)) -> float:
    """max/min over ``points`` of the first front's windowed slip at the site nearest each point (Sec. 3.4:
    under T0 all locations slip alike)."""
    fr = run.fronts()
    if not fr:
        return math.nan
    f = fr[0]
    it, ux = run.interface["intact"], run.interface["ux"]
    m = int(round(MARGIN / float(np.median(np.diff(run.times)))))
    vals = []
    for x in points:
        s = int(np.argmin(np.abs(run.x - x)))
        hit = np.flatnonzero(np.isclose(f.tip["x"], run.x[s]))
        if not len(hit):
            return math.nan
        k = int(tip_frames(run, f)[hit[0]])
        k1 = min(len(run.times) - 1, rebond_frame(it, k, s) + m)
        vals.append(ux[k1, s] - ux[max(0, k - m), s])
    vals = np.abs(vals)
    return float(vals.max() / vals.min()) if vals.min() > 0 else math.inf


# --- interface stresses -------------------------------------------------------------------

def pre_break_profile(run, field: str):
    """(x, field) along the interface in the frame before the first bond breaks; (None, None) if none broke."""
    k = first_break_frame(run)
    if k is None or field not in run.interface:
        return None, None
    return run.x, run.interface[field][max(k - 1, 0)]


def argmax_before_break(run, field: str) -> float:
    """x/l where ``field`` (sxy or syy) is largest in the frame before the first break."""
    x, f = pre_break_profile(run, field)
    return math.nan if x is None else float(x[int(np.argmax(f))])


def min_before_break(run, field: str = "syy") -> float:
    """Smallest ``field`` (rho c_r^2) along the interface in the frame before the first break (for syy:
    the most compressive normal stress at nucleation)."""
    x, f = pre_break_profile(run, field)
    return math.nan if x is None else float(np.min(f))


def centre_over_edges(run, field: str = "sxy") -> float:
    """Mean ``field`` over the central 0.3-0.7 l over its mean over the outer 0.1 l at each end, in the frame
    before the first break (Sec. 3.3.3: shear stress rising from the edges to the centre)."""
    x, f = pre_break_profile(run, field)
    if x is None:
        return math.nan
    edges = float(np.mean(f[(x < 0.1) | (x > 0.9)]))
    centre = float(np.mean(f[(x >= 0.3) & (x <= 0.7)]))
    return centre / edges if edges else math.inf


def tip_peak(run, front, t: float, field: str = "sxy", sites: int = 5) -> float:
    """Largest ``field`` over the ``sites`` sites ahead of ``front``'s tip at the frame nearest ``t``."""
    from ...plot.figures import tip_profile
    _, s = tip_profile(run, front, t, field, sites)
    return float(np.max(s)) if len(s) else math.nan


def tip_peak_constancy(run) -> float:
    """max/min of the sxy peak ahead of the leading tip at the second, third and fourth nucleations
    (Sec. 3.1.3: the peak at the tip stays constant as the pulse runs); the leading tip is the
    earliest-born edge front still in flight then (the first one, while it is)."""
    fr = edge_fronts(run)
    if len(fr) < 4:
        return math.nan
    peaks = []
    for i in (1, 2, 3):
        t = fr[i].nucleation_time
        alive = [f for f in fr[:i] if f.nucleation_time < t <= float(f.tip["t"][-1])]
        peaks.append(tip_peak(run, alive[0], t) if alive else math.nan)
    if not all(math.isfinite(p) and p > 0 for p in peaks):
        return math.nan
    return max(peaks) / min(peaks)


def mode2_r2(run, front_index: int, times, sites: int = 8) -> float:
    """Median R^2 of the Mode II fits (appendix B) of a front at ``times``: the straight line
    sigma^-2 = (2 pi / K^2) xi + 2 pi x_p / K^2 through the ``sites`` sites ahead of its tip.  A fit with
    K_II undefined (sigma^-2 not rising with xi) counts as R^2 = 0."""
    from ...plot.figures import tip_profile
    fr = run.fronts()
    if len(fr) <= front_index:
        return math.nan
    f = fr[front_index]
    out = []
    for t in times:
        if not f.nucleation_time < t <= f.tip["t"][-1]:
            continue
        xi, s = tip_profile(run, f, t, "sxy", sites)
        k2, _ = mode2_fit_shifted(xi, s)
        if len(xi) < 3 or not math.isfinite(k2):
            out.append(0.0)
            continue
        y = 1.0 / s ** 2
        a, b = np.polyfit(xi, y, 1)
        ss = float(np.sum((y - y.mean()) ** 2))
        out.append(1.0 - float(np.sum((y - (a * xi + b)) ** 2)) / ss if ss > 0 else 0.0)
    return float(np.median(out)) if out else math.nan


def mode2_first_pulse(run) -> float:
    """``mode2_r2`` of the first edge front at four moments of its steady run (appendix B, Fig. B1)."""
    fr = edge_fronts(run)
    if not fr:
        return math.nan
    f = fr[0]
    i = run.fronts().index(f)
    d = np.abs(f.tip["x"] - f.nucleation_x)
    tt = f.tip["t"][(d >= 0.1) & (d <= 0.6)]
    if len(tt) < 4:
        return math.nan
    return mode2_r2(run, i, [float(tt[int(q * (len(tt) - 1))]) for q in (0.0, 1 / 3, 2 / 3, 1.0)])


def mode2_later_pulses(run) -> float:
    """The smaller ``mode2_r2`` of the second and third edge fronts at the fourth nucleation (Fig. B2)."""
    fr = edge_fronts(run)
    if len(fr) < 4:
        return math.nan
    t = fr[3].nucleation_time
    r = [mode2_r2(run, run.fronts().index(fr[i]), [t]) for i in (1, 2)]
    return min(r) if all(math.isfinite(v) for v in r) else math.nan


def tip_carries_both_peaks(run, sites: int = 5) -> float:
    """At the first front's mid-crossing frame: the share of sxy and syy (0, 0.5 or 1) whose largest value
    over the bonded sites lies within ``sites`` sites ahead of the tip (Sec. 3.3.3: peaks in both
    components travel with the T0 rupture)."""
    fr = run.fronts()
    if not fr:
        return math.nan
    f = fr[0]
    tt = f.tip["t"]
    t = float(tt[len(tt) // 2])
    k = run.frame_at(t)
    x_tip = f.tip_at(run.times[k])
    xi = f.direction * (run.x - x_tip)
    bonded = run.interface["intact"][k] == 1
    if not bonded.any():
        return math.nan
    hits = 0
    dx = float(np.median(np.diff(run.x))) if len(run.x) > 1 else 1.0
    for field in ("sxy", "syy"):
        v = np.where(bonded, run.interface[field][k], -np.inf)
        j = int(np.argmax(v))
        hits += 0 < xi[j] <= sites * dx + 1e-12
    return hits / 2


# --- re-attachment behind a fast front ----------------------------------------------------

def rebond_after_crossing(run, front_index: int = 0) -> float:
    """Time (l/c_r) from the front's tip reaching its last site to the first re-bonding of a site it broke:
    >= 0 when re-attachment starts only after the front crossed (Sec. 3.3.1's crack), < 0 for a pulse."""
    fr = run.fronts()
    if len(fr) <= front_index:
        return math.nan
    f = fr[front_index]
    it = run.interface["intact"]
    t_end = float(f.tip["t"][-1])
    first = math.inf
    for xx, k in zip(f.tip["x"], tip_frames(run, f)):
        s = int(np.argmin(np.abs(run.x - xx)))
        on = np.flatnonzero(it[k:, s] == 1)
        if len(on):
            first = min(first, float(run.times[k + on[0]]))
    return first - t_end if math.isfinite(first) else math.inf


def rebond_unevenness(run, front_index: int = 0) -> float:
    """Longest over median time (l/c_r each) that the sites a front broke stay broken (Sec. 3.3.1, 4.4:
    re-bonding is uneven, some regions stay detached much longer)."""
    fr = run.fronts()
    if len(fr) <= front_index:
        return math.nan
    f = fr[front_index]
    it = run.interface["intact"]
    d = []
    for xx, k in zip(f.tip["x"], tip_frames(run, f)):
        s = int(np.argmin(np.abs(run.x - xx)))
        d.append(float(run.times[rebond_frame(it, k, s)] - run.times[k]))
    d = np.array(d)
    med = float(np.median(d))
    return float(d.max() / med) if med > 0 else math.nan


def broken_share_at_crossing(run, front_index: int = 0) -> float:
    """Largest share of the contact broken at once while the front runs (1 for a crack that opens all)."""
    fr = run.fronts()
    if len(fr) <= front_index:
        return math.nan
    f = fr[front_index]
    k0, k1 = run.frame_at(f.nucleation_time), run.frame_at(float(f.tip["t"][-1]))
    it = run.interface["intact"][k0:k1 + 1]
    return float(np.max(np.mean(it == 0, axis=1))) if len(it) else math.nan


# --- snapshots --------------------------------------------------------------------------

def mean_block_sxx(run, t: float) -> float:
    """Mean sigma_xx (rho c_r^2) over the top block in the snapshot nearest ``t``; NaN without snapshots."""
    if not len(run.snapshot_times):
        return math.nan
    mesh = run.snapshot_at(t)
    rows = run.scene["lattice.bottom_rows"]
    if run.scene["lattice.substrate"] == "rigid":
        rows = 1
    y_cut = (rows - 1) * math.sqrt(3) / 2 + run.scene.get("interface.delta0", 0.5) / 2
    top = np.asarray(mesh.points)[:, 1] > y_cut
    return float(np.mean(np.asarray(mesh.point_data["sxx"])[top])) if top.any() else math.nan


def speed_ratio(pull, push, n: int = 2, how: str = "steady") -> float:
    """T+ / T- speed of the first ``n`` edge fronts: ``steady`` (``steady_speed``) or ``mean`` (each front's
    mean speed over its whole run, acceleration included), both in c_r."""
    def v(run):
        fr = edge_fronts(run)[:n]
        return float(np.mean([steady_speed(f) if how == "steady" else abs(f.mean_speed) for f in fr])) \
            if fr else math.nan
    return v(pull) / v(push)


def v_over_v0_spread(runs: list) -> float:
    """max/min over runs at different v0 of (mean steady speed / v0): 1 when v is proportional to v0."""
    vals = [mean_steady_speed(r) / r.v0 for r in runs]
    if len(vals) < 2 or not all(math.isfinite(v) and v > 0 for v in vals):
        return math.nan
    return max(vals) / min(vals)
