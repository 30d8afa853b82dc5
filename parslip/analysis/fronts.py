"""Rupture fronts from the interface record: detection, tip trajectory, kind, width, slip.

Responsible for the front catalogue that ``parslip fronts``, ``parslip run``'s
summary, the figures and the accuracy study share: when and where bonds
first break, and each rupture front with its nucleation point, direction,
tip trajectory and local speed, pulse-or-crack kind, width and the slip it
carries.  Also the paper-style space-time PNG (intact bonds yellow, broken
white).  Units: x and slip in l, t in l/c_r, so speeds come out in c_r;
widths in lattice spacings a (one site = one a).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..io.contract import EVENT_BREAK, read_interface

# l/c_r: the longest pause of a tip whose bond re-attached before it moved on, for its front to stay one
# front (the detector's patience); the default of every function that groups breaks into fronts.
MAX_GAP = 3.0


def load_interface(path: str) -> dict:
    """The interface record (``io.contract.read_interface``): x, t, intact, partner, ux, uy, sxy, syy."""
    return read_interface(path)


def first_break(iface: dict):
    """(t, x) of the first bond break: time in l/c_r, the x (l) of the sites that broke then.  Exact to the
    time step from the event record (the drive phase's first break: ramp and settle are the preparation);
    from the frames (the first frame with a broken bond) for files written before events existed."""
    ev = iface.get("events")
    if ev is not None:
        hit = np.flatnonzero((ev["kind"] == EVENT_BREAK) & (ev["step"] >= 0))
        if len(hit) == 0:
            return None, np.zeros(0)
        first = ev["step"][hit[0]]
        sites = ev["site"][hit][ev["step"][hit] == first]
        return float(ev["time"][hit[0]]), iface["x"][np.unique(sites)]
    broken = iface["intact"] == 0
    rows = np.flatnonzero(broken.any(axis=1))
    if len(rows) == 0:
        return None, np.zeros(0)
    k = rows[0]
    return float(iface["t"][k]), iface["x"][broken[k]]


@dataclass
class Front:
    """One rupture front.  Times in l/c_r, positions and slip in l, speeds in c_r (signed: + toward x/l = 1).

    ``tip`` holds arrays along the tip trajectory, one entry per site the tip
    reached, in the order it reached them:
      t, x     arrival time of the tip at the site and the site's x (x_tip(t))
      v        local tip speed v(x_tip), signed: 1 / (d t_arr / d x) fitted over 2 h + 1 sites
      w        width of the broken zone behind the tip at that moment, in a
      du, dv   slip the front carries at that site, in l: the change of u between the
               midpoints in time to the neighbouring fronts' passages there (``_slip_windows``)
      u_behind, v_behind   displacement of the site just behind the tip when the tip
               arrives, from its value at t = 0 (the loaded equilibrium), in l (Sec. 3.4)
      frame    the first interface frame that shows the site broken (the frame the slip and
               u_behind are read at)
      step     (from events) the drive step of the site's break: t = step dt exactly
    """
    nucleation_time: float
    nucleation_x: float
    direction: int              # +1 toward x/l = 1, -1 toward x/l = 0, 0 if it did not move
    kind: str                   # "pulse" (bonds re-attach behind the tip) or "crack"
    mean_speed: float           # (x_last - x_first) / (t_last - t_first), signed, c_r
    max_speed: float            # local speed of largest magnitude, signed, c_r (bursts left out)
    steady_speed: float         # |speed| fitted over the middle 60 % of the sites, c_r
    accel_x: float | None       # first x_tip where |v| exceeds ACCEL_FACTOR x the early median speed
    width: float                # median width of the broken zone behind the tip, a
    slip_u: float               # median of tip["du"], l
    slip_v: float               # median of tip["dv"], l
    tip: dict = field(repr=False)
    resolution: float = math.nan   # time resolution of the arrival times, l/c_r: dt (events) or a frame
    fit_sites: int = 5          # sites in each local speed fit (2 window + 1)
    # Stretches of the tip's path, each {"sites": [first, last], "x": [x0, x1] (l), "t": [t0, t1] (l/c_r),
    # "n_sites", "n_steps" (distinct break steps), "max_speed" (c_r, unsigned; None for a burst)}:
    supershear: list = field(default_factory=list)   # local speed above c_s (and at most c_l)
    bursts: list = field(default_factory=list)       # fits above c_l: near-simultaneous breaks, not a speed

    # Names the run summary and older callers use.
    @property
    def t_start(self) -> float:
        return self.nucleation_time

    @property
    def x_start(self) -> float:
        return self.nucleation_x

    @property
    def t_end(self) -> float:
        return float(self.tip["t"][-1])

    @property
    def x_far(self) -> float:
        return float(self.tip["x"][-1])

    @property
    def speed(self) -> float:
        """Unsigned steady speed, c_r."""
        return self.steady_speed

    @property
    def sites(self) -> int:
        return len(self.tip["x"])

    def speed_at(self, x: float) -> float:
        """Local tip speed (signed, c_r) where the tip passed nearest to ``x`` (l)."""
        return float(self.tip["v"][int(np.argmin(np.abs(self.tip["x"] - x)))])

    def tip_at(self, t: float) -> float:
        """x_tip (l) at time ``t``: the last site reached at or before ``t`` (the nucleation site before)."""
        j = int(np.searchsorted(self.tip["t"], t, side="right")) - 1
        return float(self.tip["x"][max(j, 0)])

    def to_dict(self) -> dict:
        """JSON-ready: the README's field names; NaN becomes None."""
        def clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None
            return v
        d = {k: clean(getattr(self, k)) for k in
             ("nucleation_time", "nucleation_x", "direction", "kind", "mean_speed", "max_speed",
              "steady_speed", "accel_x", "width", "slip_u", "slip_v", "resolution", "fit_sites")}
        d["supershear"], d["bursts"] = self.supershear, self.bursts
        d["tip"] = {k: [clean(float(v)) for v in a] for k, a in self.tip.items()}
        return d


ACCEL_FACTOR = 2.0      # a front "accelerates" where |v| first exceeds this multiple of its early speed


def break_events(iface: dict) -> tuple[np.ndarray, np.ndarray]:
    """(frame, site) of every intact -> broken transition, in time order (a bond broken in frame 0 counts)."""
    broken = iface["intact"] == 0
    new = broken.copy()
    new[1:] &= ~broken[:-1]
    k, s = np.nonzero(new)
    return k, s


def _runs(sites: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous runs [a, b] of a sorted array of site indices."""
    if len(sites) == 0:
        return []
    cut = np.flatnonzero(np.diff(sites) > 1)
    starts = np.r_[sites[0], sites[cut + 1]]
    ends = np.r_[sites[cut], sites[-1]]
    return list(zip(starts.tolist(), ends.tolist()))


class _Chain:
    """Sites a front has broken, with the frame each broke in; it grows only at its tip."""

    def __init__(self, a: int, b: int, k: int):
        self.arrival = {s: k for s in range(a, b + 1)}
        self.lo, self.hi, self.d, self.last = a, b, 0, k

    def extends(self, a: int, b: int) -> int:
        """+1 / -1 if the run [a, b] newly covers the site just beyond hi / lo (in a direction still open), else 0."""
        if self.d >= 0 and a <= self.hi + 1 <= b:
            return 1
        if self.d <= 0 and a <= self.lo - 1 <= b:
            return -1
        return 0

    def grow(self, side: int, a: int, b: int, k: int) -> None:
        new = range(self.hi + 1, b + 1) if side > 0 else range(a, self.lo)
        for s in new:
            self.arrival[s] = k
        self.lo, self.hi = min(self.lo, a), max(self.hi, b)
        self.d, self.last = side, k


def chains(iface: dict, max_gap: float = MAX_GAP) -> list[_Chain]:
    """Break events grouped into fronts, frame by frame.

    In each frame the newly broken sites form contiguous runs.  A run that
    covers the site just beyond a chain's tip (hi + 1 for a chain moving
    toward x = 1, lo - 1 toward x = 0; either for a chain whose direction is
    not yet known) extends that chain, provided the chain is alive: its tip
    bond was still broken in the previous frame, or its last advance was at
    most ``max_gap`` l/c_r ago.  Among several candidates the most recently
    advanced one wins.  Any other run nucleates a new chain.  A front so
    extends only from its own tip: pulses that follow each other, or a new
    pulse nucleating where an older one passed, stay separate.
    """
    t = iface["t"]
    broken = iface["intact"] == 0
    out: list[_Chain] = []
    for k in range(broken.shape[0]):
        new = broken[k] & ~broken[k - 1] if k else broken[0]
        for a, b in _runs(np.flatnonzero(new)):
            best, side = None, 0
            for c in out:
                sd = c.extends(a, b)
                if not sd:
                    continue
                tip = c.hi if sd > 0 else c.lo
                alive = (k > 0 and broken[k - 1, tip]) or t[k] - t[c.last] <= max_gap
                if alive and (best is None or c.last > best.last):
                    best, side = c, sd
            if best is None:
                out.append(_Chain(a, b, k))
            else:
                best.grow(side, a, b, k)
    return out


def _fit_speed(xs: np.ndarray, ts: np.ndarray, d: int, dt_frame: float) -> float:
    """Signed speed d / max(d * dt_arr/dx, dt_frame / span) from arrival times ``ts`` at sites ``xs``.

    The arrival times carry the frame quantisation while x is exact, so t is
    regressed on x.  Sites the tip crossed within one frame only bound the
    speed: it is capped at their span per frame.  NaN for a single site.
    """
    span = float(np.ptp(xs))
    if span == 0:
        return math.nan
    slope = float(np.polyfit(xs, ts, 1)[0])
    return d / max(d * slope, dt_frame / span)


def _local_speed(tt: np.ndarray, xx: np.ndarray, d: int, dt_frame: float, h: int) -> np.ndarray:
    """Local tip speed at each site j: ``_fit_speed`` over sites j-h..j+h (the neighbours at a lone site)."""
    n = len(xx)
    v = np.empty(n)
    for j in range(n):
        lo, hi = max(0, j - h), min(n, j + h + 1)
        if hi - lo < 2:
            lo, hi = max(0, j - 1), min(n, j + 2)
        v[j] = _fit_speed(xx[lo:hi], tt[lo:hi], d, dt_frame)
    return v


def _front(c: _Chain, iface: dict, h: int, windows: dict) -> Front:
    t, x, intact = iface["t"], iface["x"], iface["intact"]
    nf, ns = intact.shape
    d = c.d
    order = sorted(c.arrival, reverse=(d < 0))
    s = np.array(order)
    k = np.array([c.arrival[i] for i in order])
    tt, xx = t[k], x[s]
    dt_frame = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    n = len(s)

    if d != 0:
        v = _local_speed(tt, xx, d, dt_frame, h)
        span_t = tt[-1] - tt[0]
        mean = (xx[-1] - xx[0]) / span_t if span_t > 0 else d * abs(xx[-1] - xx[0]) / dt_frame
        lo, hi = int(0.2 * n), max(int(0.8 * n), int(0.2 * n) + 2)
        steady = abs(_fit_speed(xx[lo:hi], tt[lo:hi], d, dt_frame))
        early = float(np.median(np.abs(v[: max(1, n // 2)])))
        fast = np.flatnonzero(np.abs(v) > ACCEL_FACTOR * early)
        accel = float(xx[fast[0]]) if len(fast) else None
        vmax = float(v[int(np.nanargmax(np.abs(v)))])
    else:
        v = np.full(n, np.nan)
        mean = vmax = steady = math.nan
        accel = None

    # Width: contiguous broken sites from the current tip back toward the nucleation side.
    w = np.empty(n)
    last_of_frame = {kk: j for j, kk in enumerate(k)}      # the tip at frame kk is the last site reached by then
    step = -1 if d >= 0 else 1
    for j in range(n):
        kk = k[j]
        site = s[last_of_frame[kk]]
        cnt = 0
        while 0 <= site < ns and intact[kk, site] == 0:
            cnt += 1
            site += step
        w[j] = cnt
    # Kind: a pulse if some bond behind the tip had re-attached when the tip made its last advance.
    kind = "pulse" if n > 1 and w[-1] < n else "crack"

    du, dv, ub, vb = (np.full(n, np.nan) for _ in range(4))
    if "ux" in iface and "uy" in iface:
        ux, uy = iface["ux"], iface["uy"]
        for j in range(n):
            kk, site = k[j], s[j]
            k_lo, k_hi = windows[site][kk]
            du[j] = ux[k_hi, site] - ux[k_lo, site]
            dv[j] = uy[k_hi, site] - uy[k_lo, site]
            behind = s[j - 1] if j else site
            ub[j] = ux[kk, behind] - ux[0, behind]
            vb[j] = uy[kk, behind] - uy[0, behind]

    def med(a):
        a = a[np.isfinite(a)]
        return float(np.median(a)) if len(a) else math.nan

    tip = {"t": tt.astype(float), "x": xx.astype(float), "v": v, "w": w, "du": du, "dv": dv,
           "u_behind": ub, "v_behind": vb, "frame": k.astype(np.int64)}
    return Front(float(tt[0]), float(xx[0]), int(d), kind, float(mean), vmax, float(steady), accel,
                 med(w), med(du), med(dv), tip, resolution=dt_frame, fit_sites=2 * h + 1)


def _slip_windows(kept: list[_Chain], nf: int) -> dict:
    """site -> {arrival frame: (k_lo, k_hi)}: the frames that bracket each front's passage of a site.

    The slip a front carries at a site is the displacement between the
    midpoints (in frames) to the neighbouring fronts' arrivals there: frame 0
    before the first front, the last frame after the last.  The fronts so
    share out all the motion of a site, creep included (which the paper finds
    absent between pulses), and their slips add up to its total displacement.
    """
    per_site: dict[int, list[int]] = {}
    for c in kept:
        for site, k in c.arrival.items():
            per_site.setdefault(site, []).append(k)
    out = {}
    for site, ks in per_site.items():
        ks = sorted(ks)
        bounds = [0] + [(a + b) // 2 for a, b in zip(ks, ks[1:])] + [nf - 1]
        out[site] = {k: (bounds[i], bounds[i + 1]) for i, k in enumerate(ks)}
    return out


def fronts(iface: dict, max_gap: float = MAX_GAP, min_sites: int = 5, window: int = 2) -> list[Front]:
    """Every rupture front that broke at least ``min_sites`` bonds, in order of nucleation.

    ``max_gap`` (l/c_r): longest pause of a tip whose bond re-attached before it
    advanced again; ``window``: the local speed is fitted over 2 * window + 1 sites.
    A record with bond events (``iface["events"]``, every file written since
    they exist) gives tips resolved to the time step (``event_fronts``); older
    files, tips resolved to the frame interval.
    """
    if iface.get("events") is not None:
        return event_fronts(iface, max_gap, min_sites, window)
    kept = [c for c in chains(iface, max_gap) if len(c.arrival) >= min_sites]
    windows = _slip_windows(kept, len(iface["t"]))
    out = [_front(c, iface, window, windows) for c in kept]
    out.sort(key=lambda f: (f.nucleation_time, f.nucleation_x))
    return out


def table(fr: list[Front], fates: list[str] | None = None, arrest: dict | None = None) -> str:
    """The catalogue as a readable table (units in the header); with ``fates`` (``analysis.friction.fate``)
    a column of what became of each front, and ``arrest`` {front index: arrest length in l} for precursors."""
    fates = fates or []
    arrest = arrest or {}
    extra = bool(fates)
    head = (f"{'#':>3} {'t_nuc':>8} {'x_nuc':>6} {'dir':>4} {'kind':>6} {'v_mean':>9} {'v_max':>9} "
            f"{'accel_x':>7} {'width':>6} {'slip_u':>9} {'slip_v':>9} {'sites':>5}"
            + (f" {'fate':>8} {'arrest':>6}" if extra else "") + "\n"
            f"{'':>3} {'l/c_r':>8} {'l':>6} {'':>4} {'':>6} {'c_r':>9} {'c_r':>9} "
            f"{'l':>7} {'a':>6} {'l':>9} {'l':>9} {'':>5}" + (f" {'':>8} {'l':>6}" if extra else ""))
    rows = [head]
    for i, f in enumerate(fr):
        acc = f"{f.accel_x:7.3f}" if f.accel_x is not None else f"{'-':>7}"
        row = (f"{i + 1:>3} {f.nucleation_time:8.3f} {f.nucleation_x:6.3f} {f.direction:>+4d} {f.kind:>6} "
               f"{f.mean_speed:9.3g} {f.max_speed:9.3g} {acc} {f.width:6.1f} {f.slip_u:9.3g} "
               f"{f.slip_v:9.3g} {f.sites:5d}")
        if extra:
            row += f" {fates[i]:>8} " + (f"{arrest[i]:6.3f}" if i in arrest else f"{'-':>6}")
        rows.append(row)
    return "\n".join(rows + resolution_lines(fr))


def resolution_lines(fr: list[Front]) -> list[str]:
    """What the catalogue's speeds are resolved to, and every stretch flagged as supershear or as a burst."""
    if not fr:
        return []
    f0 = fr[0]
    src = "exact break steps" if f0.tip.get("step") is not None else "interface frames"
    out = [f"speeds: tip arrival times from {src} (resolution {f0.resolution:.3g} l/c_r), each local speed "
           f"fitted over {f0.fit_sites} sites"]
    for i, f in enumerate(fr):
        for name, items in (("supershear (above c_s)", f.supershear), ("burst (fit above c_l: near-simultaneous "
                                                                      "breaks, no speed)", f.bursts)):
            for b in items:
                speed = f", up to {b['max_speed']:.3g} c_r" if b.get("max_speed") is not None else ""
                out.append(f"  front {i + 1}: {name}: sites {b['sites'][0]}-{b['sites'][1]} (x/l {b['x'][0]:.3f}-"
                           f"{b['x'][1]:.3f}), t = {b['t'][0]:.4f}-{b['t'][1]:.4f} l/c_r, {b['n_sites']} sites in "
                           f"{b['n_steps']} steps{speed}")
    return out


# --- Fronts from the exact event record ------------------------------------------------------------
# A tip reaches a site at that site's break step, so arrival times are exact to dt, not to the frame
# interval.  The grouping is ``chains``' rule applied step by step: the sites that break in one step form
# contiguous runs, and a run extends a chain when it covers the site just beyond its tip and the chain is
# alive (its tip bond still broken when the step began, or its last advance at most ``max_gap`` ago).


def _event_chains(ev: dict, n_sites: int, max_gap: float) -> tuple[list[_Chain], dict, dict]:
    """Break events grouped into fronts, step by step; returns (chains, time of each step that has events,
    {(chain id, site): broken-zone width behind the tip, in sites, when the tip reached the site})."""
    steps, sites, kinds, times = ev["step"], ev["site"], ev["kind"], ev["time"]
    broken = np.zeros(n_sites, bool)        # the bond state as the step began: every site bonded at first
    out: list[_Chain] = []
    t_of: dict[int, float] = {}
    widths: dict = {}
    ahead: dict[int, list] = {}            # site -> chains whose tip it is next to (hi + 1 or lo - 1)
    if len(steps) == 0:
        return out, t_of, widths
    cut = np.flatnonzero(np.diff(steps)) + 1
    for a, b in zip(np.r_[0, cut], np.r_[cut, len(steps)]):
        step = int(steps[a])
        t_of[step] = float(times[a])
        new = np.unique(sites[a:b][kinds[a:b] == EVENT_BREAK])
        grown = []
        for lo, hi in _runs(new):
            best, side = None, 0
            for s in range(lo, hi + 1):
                for c in ahead.get(s, ()):
                    sd = c.extends(lo, hi)
                    if not sd or c is best:
                        continue
                    tip = c.hi if sd > 0 else c.lo
                    alive = broken[tip] or t_of[step] - t_of[c.last] <= max_gap
                    if alive and (best is None or c.last > best.last):
                        best, side = c, sd
            if best is None:
                best = _Chain(lo, hi, step)
                out.append(best)
                added = range(lo, hi + 1)
            else:
                added = range(best.hi + 1, hi + 1) if side > 0 else range(lo, best.lo)
                for key in (best.hi + 1, best.lo - 1):
                    lst = ahead.get(key)
                    if lst is not None and best in lst:
                        lst.remove(best)
                best.grow(side, lo, hi, step)
            for key in ((best.hi + 1,) if best.d > 0 else (best.lo - 1,) if best.d < 0 else
                        (best.hi + 1, best.lo - 1)):
                ahead.setdefault(key, []).append(best)
            grown.append((best, list(added)))
        for e in range(a, b):
            broken[sites[e]] = kinds[e] == EVENT_BREAK
        for c, added in grown:               # the broken zone behind the tip once the step's events are in
            site, step_back = (c.hi, -1) if c.d >= 0 else (c.lo, 1)
            w = 0
            while 0 <= site < n_sites and broken[site]:
                w += 1
                site += step_back
            for s in added:
                widths[(id(c), s)] = w
    return out, t_of, widths


def _window_speed(tt: np.ndarray, xx: np.ndarray, d: int, res: float, m: int) -> np.ndarray:
    """Local tip speed at each site: ``_fit_speed`` over ``m`` consecutive sites of the path, centred on the
    site where the path allows and shifted inward near its ends (every fit spans ``m`` sites when the path
    has as many)."""
    n = len(xx)
    v = np.empty(n)
    for j in range(n):
        lo = min(max(0, j - m // 2), max(n - m, 0))
        v[j] = _fit_speed(xx[lo:lo + m], tt[lo:lo + m], d, res)
    return v


def _segments(idx: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous runs [i, j] of a sorted array of positions along a tip path."""
    return _runs(idx)


def _stretches(idx, s, xx, tt, steps, v) -> list[dict]:
    out = []
    for i, j in _segments(np.flatnonzero(idx)):
        vv = np.abs(v[i:j + 1])
        vv = vv[np.isfinite(vv)]
        out.append({"sites": [int(s[i]), int(s[j])], "x": [float(xx[i]), float(xx[j])],
                    "t": [float(tt[i]), float(tt[j])], "n_sites": int(j - i + 1),
                    "n_steps": int(len(np.unique(steps[i:j + 1]))),
                    "max_speed": float(vv.max()) if len(vv) else None})
    return out


def _event_front(c: _Chain, iface: dict, h: int, t_of: dict, widths: dict, windows: dict) -> Front:
    """One front from its chain of exact arrival steps (see ``Front``)."""
    ev = iface["events"]
    res, c_s, c_l = ev["dt"], ev["c_s"], ev["c_l"]
    x = iface["x"]
    d = c.d
    order = sorted(c.arrival, reverse=(d < 0))
    s = np.array(order)
    steps = np.array([c.arrival[i] for i in order])
    tt, xx = np.array([t_of[k] for k in steps]), x[s]
    n = len(s)
    supershear, bursts = [], []
    if d != 0:
        v = _window_speed(tt, xx, d, res, 2 * h + 1)
        fast = np.abs(v) > c_l            # a fit above c_l: breaks too close in time for any signal
        bursts = _stretches(fast, s, xx, tt, steps, np.full(n, np.nan))
        v = np.where(fast, np.nan, v)
        supershear = _stretches(np.abs(v) > c_s, s, xx, tt, steps, v)
        span_t = tt[-1] - tt[0]
        mean = (xx[-1] - xx[0]) / span_t if span_t > 0 else math.nan
        if abs(mean) > c_l:
            mean = math.nan
        lo, hi = int(0.2 * n), max(int(0.8 * n), int(0.2 * n) + 2)
        steady = abs(_fit_speed(xx[lo:hi], tt[lo:hi], d, res))
        if steady > c_l:
            steady = math.nan
        finite = np.isfinite(v)
        early = float(np.median(np.abs(v[: max(1, n // 2)][finite[: max(1, n // 2)]]))) \
            if finite[: max(1, n // 2)].any() else math.nan
        accel_at = np.flatnonzero(np.abs(np.nan_to_num(v)) > ACCEL_FACTOR * early) if math.isfinite(early) else []
        accel = float(xx[accel_at[0]]) if len(accel_at) else None
        vmax = float(v[int(np.nanargmax(np.abs(v)))]) if finite.any() else math.nan
    else:
        v = np.full(n, np.nan)
        mean = vmax = steady = math.nan
        accel = None
    w = np.array([widths.get((id(c), int(i)), 1) for i in s], float)
    kind = "pulse" if n > 1 and w[-1] < n else "crack"

    du, dv, ub, vb = (np.full(n, np.nan) for _ in range(4))
    if "ux" in iface and "uy" in iface and len(iface["t"]):
        ux, uy = iface["ux"], iface["uy"]
        for j in range(n):
            kk, site = c.frame_of[int(s[j])], int(s[j])
            k_lo, k_hi = windows[site][kk]
            du[j] = ux[k_hi, site] - ux[k_lo, site]
            dv[j] = uy[k_hi, site] - uy[k_lo, site]
            behind = int(s[j - 1]) if j else site
            ub[j] = ux[kk, behind] - ux[0, behind]
            vb[j] = uy[kk, behind] - uy[0, behind]

    def med(a):
        a = a[np.isfinite(a)]
        return float(np.median(a)) if len(a) else math.nan

    tip = {"t": tt.astype(float), "x": xx.astype(float), "v": v, "w": w, "du": du, "dv": dv,
           "u_behind": ub, "v_behind": vb, "step": steps.astype(np.int64),
           "frame": np.array([c.frame_of[int(i)] for i in s], np.int64)}
    return Front(float(tt[0]), float(xx[0]), int(d), kind, float(mean), vmax, float(steady), accel,
                 med(w), med(du), med(dv), tip, resolution=float(res), fit_sites=2 * h + 1,
                 supershear=supershear, bursts=bursts)


def event_fronts(iface: dict, max_gap: float = MAX_GAP, min_sites: int = 5, window: int = 2) -> list[Front]:
    """``fronts`` from the exact event record ``iface["events"]``: arrival times resolved to dt.

    Local speeds are fitted over 2 ``window`` + 1 sites.  A fit above the top block's c_l is no speed: the
    sites broke too close in time for any signal to have run between them (a burst of near-simultaneous
    breaks); it is reported in ``Front.bursts`` with its sites and times and left out of every speed.
    Local speeds above c_s are reported in ``Front.supershear``.  The slip and the displacement behind the
    tip are read off the frames (the first frame after the break)."""
    ev = iface["events"]
    kept_all, t_of, widths = _event_chains(ev, len(iface["x"]), max_gap)
    kept = [c for c in kept_all if len(c.arrival) >= min_sites]
    # The first frame that shows each break (a frame records the bonds as they entered its step).
    fsteps = iface.get("step")
    nf = len(iface["t"])
    for c in kept:
        if fsteps is not None and nf:
            c.frame_of = {i: int(min(np.searchsorted(fsteps, k, side="right"), nf - 1)) for i, k in c.arrival.items()}
        else:
            c.frame_of = {i: 0 for i in c.arrival}
    framed = []
    for c in kept:                            # the frame-indexed view ``_slip_windows`` works on
        fc = _Chain.__new__(_Chain)
        fc.arrival = c.frame_of
        framed.append(fc)
    windows = _slip_windows(framed, nf) if nf else {}
    out = [_event_front(c, iface, window, t_of, widths, windows) for c in kept]
    out.sort(key=lambda f: (f.nucleation_time, f.nucleation_x))
    return out
