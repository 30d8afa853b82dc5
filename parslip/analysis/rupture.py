"""Measures of rupture as a crack: what a front released and how it ran, from the run (``analysis.results
.Run``: its catalogue and interface record); no file access, no drawing.  The catalogue options
(``max_gap``, ``min_sites``, ``window``) pass through to ``run.fronts``.

andrews_s(run, front)           Andrews' seismic ratio S = (tau_peak - tau_0) / (tau_0 - tau_res) per site
                                along the front's path, and its median (the 2D supershear threshold is
                                S ~ 1.77); the per-front field ``andrews_s`` is that median
daughters(run)                  fronts born ahead of a running front's tip (the Burridge-Andrews daughter)
andrews_lc, andrews_f           Andrews' (1976) critical half-length L_c and his transition factor f(S) as Xia
                                et al. (Science 2004) fit it: L_trans = f(S) L_c (the formulas live in ``lefm``)
law_scales(setup)               a scene's own scales before any run: the law's tau_p, tau_r, Gamma, Palmer &
                                Rice's Lambda, and with a held prestress tau_0, S and Andrews' L_c
transition(run, front)          where a front went supershear: the distance from its nucleation at which a
                                daughter was born ahead of it (or its tip first ran above c_s), Andrews'
                                L_trans for the S measured on it, and the speed the supershear front settled at
speed_summary(run)              the largest local speed fitted over the catalogue's window, and how many
                                sites ran above c_s or broke in bursts
through_patch(front, lo, hi)    how a front met a patch [lo, hi) of the contact: its mean speed before,
                                inside and after it, and whether it got through
traction_drop (per-front field) the mean drop of the shear traction at the sites the front broke

Units: x in l, t in l/c_r, speeds in c_r, tractions in rho c_r^2 (``/interface/sxy``).
"""
from __future__ import annotations

import math

import numpy as np

from ..io.contract import EVENT_BREAK
from ..model.physics import DENSITY
from .fronts import Front, front_field, wave_speeds
from .lefm import ANDREWS_F_COEF, ANDREWS_S_2D, andrews_f, andrews_lc  # noqa: F401  (measures' formulas)


def _sites(iface: dict, front: Front) -> np.ndarray:
    """Indices of the sites on the front's path, in the order its tip reached them."""
    return np.clip(np.rint(np.asarray(front.tip["x"]) * len(iface["x"]) - 0.5).astype(int), 0, len(iface["x"]) - 1)


# l/c_r: the window behind the tip over which a site's residual traction is averaged (a broken bond carries
# none): about the time a paper pulse takes to pass a site, so tau_res is the traction the front leaves.
RES_WINDOW = 1.0


def _break_tractions(run, front: Front) -> np.ndarray | None:
    """The shear traction (rho c_r^2) of each of the front's sites at the step it broke, from the event
    record's ``traction`` (``/interface/events/traction``); None when the record has no such field."""
    ev = run.events
    if ev is None or "traction" not in ev or "step" not in front.tip:
        return None
    hit = np.flatnonzero(ev["kind"] == EVENT_BREAK)
    at = {(int(k), int(st)): float(tr) for k, st, tr in zip(ev["step"][hit], ev["site"][hit], ev["traction"][hit])}
    sites = _sites(run.interface, front)
    return np.array([at.get((int(k), int(st)), math.nan) for k, st in zip(front.tip["step"], sites)])


def andrews_s(run, front: Front, window: float = RES_WINDOW, t0: float | None = None) -> dict:
    """Andrews' seismic ratio S = (tau_peak - tau_0) / (tau_0 - tau_res), per site along the front's path,
    then summarised; tractions are the interface shear traction sxy (rho c_r^2).  Per site s the tip reached:

      tau_0     the traction the front runs into: s's traction in the last frame before the front's first
                break shows (the frame before its nucleation), or before time ``t0`` (l/c_r) when given: a
                front that sat at a patch while the load rose ran into the traction of when it left
      tau_peak  s's traction at the step its bond broke, from the event record (``traction``); a file
                without it falls back on the frames, the largest traction s showed from tau_0's frame to
                the last frame before its break (which may miss the peak: ``peak_from`` says "frames")
      tau_res   the mean traction at s over ``window`` l/c_r from the first frame that shows its break, a
                broken bond counting 0 (it carries no force until it re-forms)

    Tractions are taken with the sign of the path's median tau_peak, so S does not depend on the drive's
    direction.  Returns {"S": the median over the sites where tau_0 - tau_res > 0 (something was released),
    "tau_0", "tau_peak", "tau_res": their medians, "peak_from": "events" or "frames", "window", "sites":
    {"S", "tau_0", "tau_peak", "tau_res"} per site in the tip's order}; NaN where nothing was released or
    the record holds no sxy."""
    iface = run.interface
    nan = {"S": math.nan, "tau_0": math.nan, "tau_peak": math.nan, "tau_res": math.nan, "peak_from": None,
           "window": window, "sites": {}}
    if "sxy" not in iface or len(front.tip["t"]) == 0:
        return nan
    sxy = np.asarray(iface["sxy"], float) * (np.asarray(iface["intact"]) != 0)    # a broken bond carries 0
    t, sites = np.asarray(iface["t"], float), _sites(iface, front)
    frames = np.clip(np.asarray(front.tip["frame"], int), 0, len(t) - 1)
    k0 = max(int(frames[0]) - 1, 0) if t0 is None else max(int(np.searchsorted(t, t0)) - 1, 0)
    peak = _break_tractions(run, front)
    peak_from = "events" if peak is not None else "frames"
    if peak is None:                      # the frames' extreme before the break, in the direction of the load
        sign0 = 1.0 if np.median(sxy[k0, sites]) >= 0 else -1.0
        peak = np.array([sign0 * (sign0 * sxy[k0:max(k, k0 + 1), s]).max() for s, k in zip(sites, frames)])
    sign = 1.0 if np.median(peak) >= 0 else -1.0
    n_w = max(1, int(round(window / float(np.median(np.diff(t))))) if len(t) > 1 else 1)
    tau_0 = sign * sxy[k0, sites]
    tau_peak = sign * peak
    tau_res = sign * np.array([sxy[k:k + n_w, s].mean() for s, k in zip(sites, frames)])
    released = tau_0 - tau_res
    S = np.where(released > 0, (tau_peak - tau_0) / np.where(released > 0, released, 1.0), math.nan)
    ok = np.isfinite(S)

    def med(a):
        return float(np.median(a[ok])) if ok.any() else math.nan
    return {"S": med(S), "tau_0": med(tau_0), "tau_peak": med(tau_peak), "tau_res": med(tau_res),
            "peak_from": peak_from, "window": window,
            "sites": {"S": S, "tau_0": tau_0, "tau_peak": tau_peak, "tau_res": tau_res}}


@front_field("andrews_s", "-", "Andrews' S = (tau_peak - tau_0) / (tau_0 - tau_res), the median over the "
             "front's path of each site's S: tau_0 its traction before the front nucleated, tau_peak at the "
             "step it broke (the event's traction; the frames' largest when the file has none), tau_res its "
             "mean over 1 l/c_r behind the tip, 0 while the bond is broken (rupture.andrews_s)")
def andrews_s_field(run, front: Front) -> float:
    """The median S of ``andrews_s`` (its per-site values and the three tractions: call it directly)."""
    return andrews_s(run, front)["S"]


def daughters(run, min_gap: float = 0.02, **kw) -> list[dict]:
    """Every front born ahead of another, running front's tip, in its direction of travel, by at least
    ``min_gap`` (l; 2 sites of a 100-site contact): {"mother", "daughter" (catalogue indices), "t" (its
    nucleation, l/c_r), "x" (l), "ahead" (l from the mother's tip then)}."""
    fronts = run.fronts(**kw)
    out = []
    for i, m in enumerate(fronts):
        if m.direction == 0:
            continue
        for j, d in enumerate(fronts):
            if j == i or not (m.nucleation_time < d.nucleation_time < m.t_end):
                continue
            tip = m.tip_at(d.nucleation_time)           # the mother has begun: d is born after it
            ahead = (d.nucleation_x - tip) * m.direction
            if ahead >= min_gap:
                out.append({"mother": i, "daughter": j, "t": d.nucleation_time, "x": d.nucleation_x,
                            "ahead": float(ahead)})
    return out


def law_scales(setup) -> dict:
    """The interface law's scales of a scene (``scene.derive.Setup``), from the scene alone, as ``parslip info``
    prints them: at rest under F_N (``model.interface.InterfaceLaw.strength``), the means over the sites of
    the held prestress's stretch (``drive.prestress.x``; the whole contact without one) of

        tau_p   the peak shear traction k_x x_b / a, x_b = sqrt(delta_b^2 - gap^2) (rho c_r^2)
        tau_r   the residual mu F_N / (N a), at most tau_p (rho c_r^2; 0 without contact friction)
        D_c     the weakening distance (a)
        Gamma   the fracture energy tau_p x_b / 2 + (tau_p - tau_r) D_c / 2 per unit length (m c_r^2 / a)

    and from them, with M the block's static mode II modulus (1 / H(0) of the Born continuum,
    ``cracks.mode2_compliance``; m c^2/a^2):

        Lambda  = 9 pi / 16  M Gamma / (tau_p - tau_r)^2                   (a)  Palmer & Rice's process zone
        S       = (tau_p - tau_0) / (tau_0 - tau_r)                              Andrews' seismic ratio
        L_c     = 2 M Gamma / (pi (tau_0 - tau_r)^2)                       (a)  Andrews' critical half-length

    (``andrews_lc`` with (tau_p - tau_r) D_c = 2 Gamma), tau_0 = drive.prestress.tau0; tau_0, S and L_c are
    NaN without a held prestress.  At D_c = 0 and tau_r = 0, Lambda is ``cracks.palmer_rice_length``."""
    from .cracks import PALMER_RICE, mode2_compliance
    st, law, mat = setup, setup.law, setup.material
    n = st.lattice.n_top_sites
    held = st.drive.prestress
    lo, hi = held.sites(n) if held is not None else (0, n)
    v = law.strength(n, st.scene["load.FN"])
    mean = {k: float(np.mean(v[k][lo:hi])) for k in ("tau_p", "tau_r", "D_c", "Gamma", "x_b")}
    M = 1.0 / mode2_compliance(0.0, mat.kn_top, mat.kt_top)
    unit = DENSITY * mat.c_r ** 2                          # one rho c_r^2 in internal stress
    tp, tr, gamma = mean["tau_p"], mean["tau_r"], mean["Gamma"]
    out = {"tau_p": tp / unit, "tau_r": tr / unit, "D_c": mean["D_c"], "x_b": mean["x_b"],
           "Gamma": gamma / mat.c_r ** 2, "M": M, "Lambda": PALMER_RICE * M * gamma / (tp - tr) ** 2,
           "tau_0": math.nan, "S": math.nan, "L_c": math.nan}
    if held is not None:
        t0 = held.tau0 * unit
        out.update(tau_0=held.tau0, S=(tp - t0) / (t0 - tr) if t0 > tr else math.inf,
                   L_c=2.0 * M * gamma / (math.pi * (t0 - tr) ** 2) if t0 > tr else math.inf)
    return out


def _modulus_and_stress_unit(run) -> tuple[float, float]:
    """The block's static mode II modulus M = 1 / H(0) (internal stress units, m c^2 / a^2) and the internal
    stress of one rho c_r^2 (the unit of ``/interface/sxy``)."""
    from .cracks import _material, mode2_compliance
    m = _material(run)
    return 1.0 / mode2_compliance(0.0, m.kn_top, m.kt_top), DENSITY * m.c_r * m.c_r


# Sites over which the tip must run above c_s for its transition: about a process zone (Lambda = 17 a at
# k_x = 0.1); over 10 sites the arrivals' jitter alone lifts a tip at c_R above c_s.
MIN_SUPERSHEAR_SITES = 20


def _first_supershear(front: Front, keep, c_s: float, n: int) -> tuple[float, float]:
    """(x (l) of the first site from which the tip's arrivals over ``n`` consecutive sites, among the sites
    ``keep(x)`` holds, fit a speed above ``c_s`` and those of every kept site from there on too; that last
    speed, c_r); NaNs when there is no such site: a tip that ran at c_R (5 % below c_s in the lattice) with
    a window's jitter above c_s did not go supershear.  A straight-line fit over n sites, not the
    catalogue's local fits: a burst of near-simultaneous breaks inside the window does not hide the speed
    the tip keeps."""
    x, t = np.asarray(front.tip["x"], float), np.asarray(front.tip["t"], float)
    ok = np.array([keep(v) for v in x], bool)
    x, t = x[ok], t[ok]
    order = np.argsort(t, kind="stable")
    x, t = x[order], t[order]
    d = front.direction or 1

    def speed(a: int, b: int) -> float:
        return d * np.polyfit(t[a:b], x[a:b], 1)[0] if np.ptp(t[a:b]) > 0 else math.nan
    for i in range(len(x) - n + 1):
        if speed(i, i + n) > c_s and speed(i, len(x)) > c_s:
            return float(x[i]), float(speed(i, len(x)))
    return math.nan, math.nan


def transition(run, front: Front, origin: float | None = None, beyond: float | None = None,
               before: float | None = None, min_sites: int = MIN_SUPERSHEAR_SITES, **kw) -> dict:
    """Where ``front`` went supershear, against Andrews' curve.  Lengths in a, speeds in c_r.  Distances are
    counted from ``origin`` (x/l; default the front's nucleation, its first break: give the centre of a
    nucleation patch, Andrews' hypocentre, when the patch breaks at once), and only what happens beyond
    ``beyond`` (x/l, in the front's direction; default the origin) and short of ``before`` (x/l; default
    none) counts: the breaks of a nucleation patch, nearly simultaneous, are no transition, nor is a front
    born at a free edge or a barrier the study does not look at.

      S, tau_0, tau_peak, tau_res   ``andrews_s`` of the front (medians over its path, rho c_r^2), tau_0
                   read before the tip first passed ``beyond`` when that is given ("launch", l/c_r): a
                   front that sat at its patch while the load rose ran into the prestress of when it left
      d_c          the bond's slip at its break, D_c = x_b = tau_peak a / k_x (the sites' median k_x; a bond
                   whose rest offset is 0 holds k_x x / a up to its break)
      L_c          ``andrews_lc`` with the block's M (the Born continuum's static mode II modulus)
      L_andrews    f(S) L_c (``andrews_f``): Andrews' transition distance for the S measured
      L_trans      the distance from the origin to the birth of the first daughter born ahead of its tip
                   (``daughters``) beyond ``beyond``, NaN when none was
      L_fast       the distance from the origin to the first site (beyond ``beyond``) from which the tip ran
                   above c_s over ``min_sites`` sites (a line fitted through their arrivals), NaN when it
                   never did (speeds in c_r; the run's c_s, ``fronts.wave_speeds``)
      v_super      the speed the supershear front settled at: the daughter's steady speed (over the middle
                   60 % of its sites) when there is one, else the mother's, fitted from L_fast on
      daughter     the daughter's catalogue index, or None."""
    l = float(run.scene["lattice.top_cols"])
    M, unit = _modulus_and_stress_unit(run)
    x0 = front.nucleation_x if origin is None else origin
    edge = x0 if beyond is None else beyond
    d = front.direction or 1
    gone = (np.asarray(front.tip["x"], float) - edge) * d > 0          # the tip beyond ``beyond``
    launch = float(np.asarray(front.tip["t"], float)[gone].min()) if beyond is not None and gone.any() else None
    s = andrews_s(run, front, t0=launch)
    kx = float(np.median(run.interface["kx"])) if "kx" in run.interface else float(run.scene["interface.kx"])
    tp, t0, tr = (s[k] * unit for k in ("tau_peak", "tau_0", "tau_res"))
    d_c = tp / kx
    L_c = float(andrews_lc(M, tp, t0, tr, d_c))
    fronts = run.fronts(**kw)
    me = next((i for i, f in enumerate(fronts) if f is front or (f.nucleation_time == front.nucleation_time
               and f.nucleation_x == front.nucleation_x)), None)

    def past(x: float) -> bool:
        return (x - edge) * d > 0 and (before is None or (before - x) * d > 0)
    kids = sorted((k for k in daughters(run, **kw) if k["mother"] == me and past(k["x"])),
                  key=lambda k: k["t"])
    L_trans, v_super, kid = math.nan, math.nan, None
    if kids:
        kid = kids[0]["daughter"]
        L_trans = abs(kids[0]["x"] - x0) * l
        v_super = abs(fronts[kid].steady_speed)
    L_fast, v_fast = _first_supershear(front, past, wave_speeds(run)["c_s"], min_sites)
    if math.isfinite(L_fast):
        L_fast = abs(L_fast - x0) * l
        if kid is None:
            v_super = v_fast
    return {"launch": launch, "S": s["S"], "tau_0": s["tau_0"], "tau_peak": s["tau_peak"],
            "tau_res": s["tau_res"], "d_c": d_c, "L_c": L_c, "L_andrews": float(L_c * andrews_f(s["S"])),
            "L_trans": L_trans, "L_fast": L_fast, "v_super": v_super, "daughter": kid}


def speed_summary(run, **kw) -> dict:
    """{"max_speed" (the largest |max_speed| of the fronts, over the catalogue's fit window, bursts
    included: ``Front.band`` says which band it is in), "supershear_sites" (sites run above c_s, over all
    fronts), "supershear_fronts" (how many fronts had such a stretch), "burst_sites" (sites broken in
    bursts faster than every wave speed: near-simultaneous breaks, no speed)}."""
    fronts = run.fronts(**kw)
    speeds = [abs(f.max_speed) for f in fronts if math.isfinite(f.max_speed)]
    return {"max_speed": max(speeds) if speeds else math.nan,
            "supershear_sites": sum(s["n_sites"] for f in fronts for s in f.supershear),
            "supershear_fronts": sum(1 for f in fronts if f.supershear),
            "burst_sites": sum(b["n_sites"] for f in fronts for b in f.bursts)}


def through_patch(front: Front, lo: float, hi: float, c_l: float = math.inf) -> dict:
    """How ``front`` met the patch [lo, hi) (l): its mean speed over the stretch before the patch (as long
    as the patch), inside it, and beyond it (c_r; NaN where its tip never was, or where the "speed" exceeds
    ``c_l``: a burst of near-simultaneous breaks, counted in "bursts"), and "through": whether its tip
    reached the far side of the patch."""
    x, t = np.asarray(front.tip["x"], float), np.asarray(front.tip["t"], float)
    d = front.direction or 1
    width = hi - lo
    near, far = (lo, hi) if d > 0 else (hi, lo)

    def mean_speed(a: float, b: float) -> float:
        inside = (x >= min(a, b)) & (x < max(a, b))
        if inside.sum() < 2:
            return math.nan
        xs, ts = x[inside], t[inside]
        v = float(abs(xs[-1] - xs[0]) / (ts[-1] - ts[0])) if ts[-1] > ts[0] else math.inf
        if v > c_l:
            bursts.append((min(a, b), max(a, b)))
            return math.nan
        return v
    bursts: list = []
    out = {"before": mean_speed(near - d * width, near), "inside": mean_speed(lo, hi),
           "after": mean_speed(far, far + d * width),
           "through": bool(np.any(x >= hi) if d > 0 else np.any(x < lo))}
    out["bursts"] = len(bursts)
    return out


@front_field("traction_drop", "rho c_r^2", "mean over the front's path of the drop of the interface shear "
             "traction its tip brings: per site, sxy in the last frame before the break minus sxy in the first "
             "frame that shows it (the break from the event record), signed so that a release of the load "
             "the path carried is positive; null without sxy", "dtau", "9.3g")
def traction_drop(run, front: Front) -> float | None:
    """Mean shear-traction drop along the front's path, rho c_r^2 (``/interface/sxy``'s units).

    Per site s the tip reached, with k_s the first interface frame that shows its bond broken
    (``tip["frame"]``: the first frame after the break's step in the event record, or the frame of the break
    in a file without events):  d_tau_s = sign * (sxy[k_s - 1, s] - sxy[k_s, s]), where sign is that of
    the mean of sxy[k_s - 1, s] over the path, so a front that releases the traction the path carried
    has d_tau > 0 whichever way the drive loads it.  The value is the mean of d_tau_s over the sites with
    a frame before their break (a bond broken in frame 0 has none); None when the record holds no sxy or
    no such site.  The frames bracket the break by at most one frame interval, so d_tau_s is the drop
    over that interval."""
    iface = run.interface
    if "sxy" not in iface:
        return None
    sites = _sites(iface, front)
    frames = np.asarray(front.tip["frame"], int)
    ok = frames > 0
    if not ok.any():
        return None
    sxy = np.asarray(iface["sxy"], float)
    before, after = sxy[frames[ok] - 1, sites[ok]], sxy[frames[ok], sites[ok]]
    sign = 1.0 if np.mean(before) >= 0 else -1.0
    return float(sign * np.mean(before - after))
