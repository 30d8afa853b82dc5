"""Friction and stick-slip of a run: mu(t), the static peak mu_s, what each front did, the precursors.

Every measure is a function of the run (``analysis.results.Run``); the catalogue options (``max_gap``,
``min_sites``, ``window``) pass through to ``run.fronts``.

  mu(run)                        mu(t) = -F_T / F_N per frame (``/interface/mu``)
  slip_onset(run)                the frame by which every bond had broken once
  static_peak(run)               mu_s, its time, window and place relative to the first break (``StaticPeak``)
  fate (per-front field)         what became of a front: crossed, edge, relayed, merged, arrested, running
  crossed_contact(run, front)    whether its crossing of the contact completed (by its tip, or relayed)
  arrest_length (per-front field)  the length of contact an arrested front broke, l
  precursors(run)                the fronts that arrested inside the contact (``Precursor``)
  slip_events(run, min_drop)     the stick-slip record's drops of mu (``SlipEvent``)
  observables(run)               the one-row digest a sweep's summary table holds per point
  sinking(run)                   per frame, the depth of the block's lowest-gone interface site below its start, a
  summary(run), summary_lines(run), slip_event_lines(events)   the same as text

Definitions (x and lengths in l, t in l/c_r, speeds in c_r):

  slip onset      t_slip, the first frame by which every interface bond has broken at least once since
                  the drive began: the whole contact has then slipped, by one front crossing it or by
                  several that share it out.  Tribologists call this the onset of (macroscopic) sliding:
                  the block as a whole has moved on its substrate.  The ``edge_sites`` bonds at each end
                  (2 % of the contact, at least one) are left out, as they are when a front counts as
                  crossing: the bonds at a free corner may hold while the rest of the contact slips (on
                  a 24-site contact pushed from the rear the front edge's bond never breaks while pulse
                  after pulse arrives next to it; on 100 sites pulses stop 2 sites short).
  static peak     mu_s = max mu(t) over 0 <= t <= t_slip: the largest tangential load the interface
                  held before it had slipped everywhere, as experiments define static friction (the
                  peak shear force before the first slip event that spans the contact; Rubinstein et
                  al. 2007, Ben-David & Fineberg 2011).  A slow pulse takes a long time to cross: while
                  it does, the part of the contact ahead of it still sticks and the force may still
                  rise, so the window closes when the contact has slipped everywhere, not when the
                  crossing front nucleates.  The friction force often goes on rising after t_slip
                  (trains of pulses, each carrying a little slip); that is the sliding regime's
                  resistance, not the static peak.  When the contact never slipped everywhere within
                  the record, mu_s is the record's maximum and only a lower bound (``window`` "record").
  place           where the peak sits relative to the first break (the first frame with any broken
                  bond, ``fronts.first_break``): t_s - t_fb, "before", "at" (within one frame) or
                  "after" it; mu at the first break is kept too.
  fate            of a front, from its tip trajectory (the sites it reached) and the bonds ahead of it,
                  the first rule that holds:
                    crossed   its own tip broke bonds from one edge of the contact to the other (it
                              nucleated within ``edge_sites`` sites of one edge and reached the other);
                    edge      the same from a nucleation inside the contact: its tip reached the far edge;
                    relayed   its tip stopped short of the far edge, but every bond between its last site
                              and the far edge broke within ``max_gap`` of its last advance: another front
                              finished its way (a pulse from the driven edge that sets off the last few
                              bonds at the far edge at once, seen under pull).  Its own tip did not get
                              through, so a patch's ``through`` and its fate agree; the contact was
                              crossed all the same (``crossed_contact``);
                    merged    the bond just ahead of its tip was broken when it last advanced or broke
                              within ``max_gap``: it ran into another front's broken zone;
                    arrested  its tip stopped inside the contact with the bond ahead holding, and it did
                              not advance for longer than the detector's patience (``max_gap``) before
                              the record ended;
                    running   as arrested but within ``max_gap`` of the record's end: it may still be
                              moving, so it is not counted as arrested.
  precursor       a front that arrested: a rupture that did not cross the contact (Rubinstein et al.
                  2007), with its arrest time (its tip's last advance), arrest site and
  arrest length   the length of contact it broke, from its nucleation site to its arrest site, both
                  included: |x_arrest - x_nucleation| + 1/sites (l).  For a front from an edge, the
                  distance from that edge to where it stopped.
  rupture kind    of the run: the kind ("pulse" or "crack", ``fronts.Front.kind``) of the first front
                  that crossed the contact (``crossed_contact``: by its own tip, or relayed from an
                  edge).  When none crossed but the contact slipped everywhere all the same (a fast
                  rupture the detector saw in pieces, or fronts that shared the contact out), the kind
                  of the fronts that nucleated up to the slip onset, "mixed" if they differ; "none"
                  when the contact never slipped everywhere and no front crossed.
  mean speed      of a front, (x_last - x_first)/(t_last - t_first) (``Front.mean_speed``); the table
                  gives |mean speed| of the first crossing front and the mean |mean speed| of all fronts.
  slip per event  the mean over the fronts of the slip each carries (``Front.slip_u``, the median over
                  the sites it crossed of the change of u its passage brings).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..io.contract import EVENT_FORM
from .fronts import Front, first_break, front_field, json_value, table

EDGE_FRACTION = 0.02    # a tip within this share of the contact (at least one site) of an edge has reached it


def edge_sites(ns: int) -> int:
    """Sites at each end of a contact of ``ns`` sites that count as its edge: 2 %, at least one."""
    return max(1, int(round(EDGE_FRACTION * ns)))
FATES = ("crossed", "edge", "relayed", "merged", "arrested", "running")


@dataclass
class StaticPeak:
    """The static peak of mu(t) and where it sits (times in l/c_r, mu dimensionless, F_s in m c^2/a)."""
    mu_s: float                     # max mu over [0, slip_onset] (over the record if the contact never slipped)
    time: float                     # t of the peak (its first frame)
    frame: int
    window: str                     # "slip onset": the peak of a contact that slipped; "record": a lower bound
    slip_onset: float | None        # t_slip (None if the contact never slipped everywhere)
    first_break_time: float | None  # t of the first broken bond (None if none broke)
    first_break_x: float | None     # x of the first broken bond (the rearmost if several broke at once)
    mu_first_break: float | None    # mu at the first break
    after_first_break: float | None  # time - first_break_time (> 0: the peak came after the first break)
    place: str                      # "before", "at" (within one frame) or "after" the first break; "no break"
    force: float                    # F_s = mu_s * F_N, the static friction force

    def to_dict(self) -> dict:
        return {k: json_value(v) for k, v in self.__dict__.items()}


@dataclass
class Precursor:
    """A front that arrested inside the contact (lengths in l, times in l/c_r)."""
    index: int                      # its place in the front catalogue (0-based)
    nucleation_time: float
    nucleation_x: float
    arrest_time: float              # its tip's last advance
    arrest_x: float                 # the site where its tip stopped
    arrest_length: float            # |arrest_x - nucleation_x| + 1/sites
    kind: str
    front: Front

    def to_dict(self) -> dict:
        return {k: json_value(v) for k, v in self.__dict__.items() if k != "front"}


@dataclass
class SlipEvent:
    """One slip event of a stick-slip record: a drop of mu(t) = -F_T/F_N from a peak to a trough by at
    least the catalogue's ``min_drop`` (times in l/c_r, mu dimensionless, loader displacement in l)."""
    index: int                      # 0-based, in time order
    t_start: float                  # the peak's frame: the end of the stick phase
    t_end: float                    # the trough's frame: the end of the slip
    mu_before: float                # mu at the peak
    mu_after: float                 # mu at the trough
    drop: float                     # mu_before - mu_after
    loader: float                   # the loader's (or driven face's) displacement at the peak, l
    fronts: list                    # catalogue indices of the fronts nucleated since the previous slip ended
    precursors: list                # catalogue indices of the fronts that arrested since the previous slip
    precursor_lengths: list         # their arrest lengths, l
    precursor_mu: list              # mu at each one's arrest, F_T/F_N

    def to_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, list) else json_value(v)) for k, v in self.__dict__.items()}


def mu(run) -> np.ndarray:
    """mu(t) = -F_T / F_N per frame (``/interface/mu``); NaN for a record written without forces."""
    iface = run.interface
    if "mu" in iface:
        return np.asarray(iface["mu"], float)
    return np.full(len(iface["t"]), np.nan)


def slip_onset(run) -> int | None:
    """The first frame by which every interface bond but the ``edge_sites`` at each end has broken at
    least once, or None."""
    intact = run.interface["intact"]
    e = edge_sites(intact.shape[1])
    inner = intact[:, e:intact.shape[1] - e]
    if inner.shape[1] == 0 or inner.shape[0] == 0:
        return None
    ever = np.logical_or.accumulate(inner == 0, axis=0).all(axis=1)
    k = np.flatnonzero(ever)
    return int(k[0]) if len(k) else None


def static_peak(run) -> StaticPeak:
    """mu_s, its time and its place relative to the first break (see the module's definitions).

    The run's F_N (``load.FN``, m c^2/a) only scales mu_s into the static friction force F_s; without it
    F_s is NaN.
    """
    iface, fn = run.interface, _fn(run)
    t = np.asarray(iface["t"], float)
    m = mu(run)
    ks = slip_onset(run)
    end = len(t) if ks is None else ks + 1
    window = "record" if ks is None else "slip onset"
    seg = m[:end]
    if len(seg) == 0 or not np.any(np.isfinite(seg)):
        k = 0
        mu_s = math.nan
    else:
        k = int(np.nanargmax(seg))
        mu_s = float(seg[k])
    t_s = float(t[k]) if len(t) else math.nan
    tb, xb = first_break(iface)
    if tb is None:
        after = mu_b = x_b = None
        place = "no break"
    else:
        kb = int(np.searchsorted(t, tb))
        mu_b = float(m[kb])
        x_b = float(xb[0])
        after = t_s - tb
        dt = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
        place = "at" if abs(after) <= dt * (1 + 1e-9) else ("after" if after > 0 else "before")
    force = mu_s * fn if fn is not None and math.isfinite(mu_s) else math.nan
    return StaticPeak(mu_s, t_s, k, window, None if ks is None else float(t[ks]), tb, x_b, mu_b, after, place,
                      float(force))


def _fn(run) -> float | None:
    """The run's normal load F_N (m c^2/a), None when its scene does not say."""
    fn = run.scene.get("load.FN")
    return float(fn) if fn is not None else None


@front_field("fate", "-", "the first that holds: crossed (its own tip broke bonds from one edge of the contact "
             "to the other), edge (the same from inside the contact), relayed (its tip stopped short of the far "
             "edge, but the rest of the way broke within max_gap of its last advance: another front finished it), "
             "merged (the bond ahead of its tip was broken by another front when it stopped, or within max_gap), "
             "arrested (a precursor: its tip "
             "stopped inside the contact with the bond ahead holding, quiet for longer than max_gap before the "
             "record ends) or running (the same within max_gap of the record's end: it may still move)",
             "fate", ">8")
def fate(run, front: Front) -> str:
    """What became of a front: "crossed", "edge", "relayed", "merged", "arrested" or "running" (module
    docstring), judged with the detector's patience the front was found with (``front.max_gap``)."""
    iface, max_gap = run.interface, front.max_gap
    x, t = iface["x"], iface["t"]
    ns = len(x)
    e = edge_sites(ns)
    at_rear, at_front = _at_edges(run, front)
    if at_rear and at_front:            # a chain grows from its nucleation run to its tip: edge to edge
        return "crossed"
    d = front.direction
    if (d > 0 and at_front) or (d < 0 and at_rear):
        return "edge"
    if d != 0:
        tip = int(np.argmin(np.abs(x - front.x_far)))
        k0 = int(np.searchsorted(t, front.t_end - max_gap))
        k_end = int(np.searchsorted(t, front.t_end))
        k1 = int(np.searchsorted(t, front.t_end + max_gap, side="right"))
        broken = iface["intact"][k0:k1] == 0
        ahead = np.arange(tip + d, ns - e if d > 0 else e - 1, d)
        if len(ahead) and broken[:, ahead].any(axis=0).all():
            return "relayed"
        if 0 <= tip + d < ns and broken[k_end - k0:, tip + d].any():
            return "merged"
    return "running" if float(t[-1]) - front.t_end <= max_gap else "arrested"


@front_field("arrest_length", "l", "for an arrested front (a precursor), the length of contact it broke: "
             "|x_arrest - x_nucleation| + 1/sites; null otherwise", "arrest", "6.3f")
def arrest_length(run, front: Front) -> float | None:
    """|x_far - x_nucleation| + 1/sites (l) for a front whose fate is "arrested", else None."""
    if front.fate != "arrested":
        return None
    return abs(front.x_far - front.nucleation_x) + 1.0 / len(run.x)


def precursors(run, **kw) -> list[Precursor]:
    """Every front of ``run.fronts(**kw)`` that arrested inside the contact, with its arrest time, site and
    length."""
    return [Precursor(i, f.nucleation_time, f.nucleation_x, f.t_end, f.x_far, f.arrest_length, f.kind, f)
            for i, f in enumerate(run.fronts(**kw)) if f.fate == "arrested"]


def observables(run, **kw) -> dict:
    """One flat row of friction and front observables (the columns of a sweep's summary table).

    Keys and units: first_break_time (l/c_r), first_break_x (l), mu_first_break, mu_s, mu_s_time (l/c_r),
    mu_s_after_first_break (l/c_r), mu_s_place, mu_s_window, slip_onset_time (l/c_r), F_s (m c^2/a),
    mu_sliding (mean mu after the slip onset), n_fronts, n_pulse, n_crack, n_crossed, n_precursors,
    n_running, n_merged, precursor_arrest_mean, precursor_arrest_max (l), rupture_kind, front_speed (|mean speed|
    of the first crossing front, c_r), front_speed_mean (mean |mean speed| of all fronts, c_r),
    slip_per_event (l).  Missing values are NaN (numbers) or "" (words).
    """
    fr = run.fronts(**kw)
    pk = static_peak(run)
    fates = [f.fate for f in fr]
    pre = precursors(run, **kw)
    crossed = [f for f in fr if crossed_contact(run, f)]
    nan = math.nan
    m = mu(run)
    ks = slip_onset(run)
    sliding = m[ks:] if ks is not None else m[:0]
    speeds = [abs(f.mean_speed) for f in fr if math.isfinite(f.mean_speed)]
    slips = [f.slip_u for f in fr if math.isfinite(f.slip_u)]
    arrests = [p.arrest_length for p in pre]

    def num(v):
        return nan if v is None else float(v)

    return {
        "first_break_time": num(pk.first_break_time), "first_break_x": num(pk.first_break_x),
        "mu_first_break": num(pk.mu_first_break), "mu_s": num(pk.mu_s), "mu_s_time": num(pk.time),
        "mu_s_after_first_break": num(pk.after_first_break), "mu_s_place": pk.place, "mu_s_window": pk.window,
        "slip_onset_time": num(pk.slip_onset), "F_s": num(pk.force),
        "mu_sliding": float(np.nanmean(sliding)) if len(sliding) and np.any(np.isfinite(sliding)) else nan,
        "n_fronts": len(fr), "n_pulse": sum(f.kind == "pulse" for f in fr),
        "n_crack": sum(f.kind == "crack" for f in fr), "n_crossed": len(crossed), "n_precursors": len(pre),
        "n_running": fates.count("running"), "n_merged": fates.count("merged"),
        "precursor_arrest_mean": float(np.mean(arrests)) if arrests else nan,
        "precursor_arrest_max": float(np.max(arrests)) if arrests else nan,
        "rupture_kind": rupture_kind(fr, crossed, pk.slip_onset),
        "front_speed": abs(crossed[0].mean_speed) if crossed else nan,
        "front_speed_mean": float(np.mean(speeds)) if speeds else nan,
        "slip_per_event": float(np.mean(slips)) if slips else nan,
    }


def _at_edges(run, front: Front) -> tuple[bool, bool]:
    """Whether the front's path reached the rear (x/l = 0) and the front (x/l = 1) edge of the contact, within
    ``edge_sites`` sites."""
    x = run.x
    tol = (edge_sites(len(x)) + 0.5) / len(x)
    return float(front.tip["x"].min()) <= x[0] + tol, float(front.tip["x"].max()) >= x[-1] - tol


def crossed_contact(run, front: Front) -> bool:
    """Whether the front's crossing of the contact completed: it crossed edge to edge by its own tip, or it
    nucleated at an edge and was relayed to the other."""
    return front.fate == "crossed" or (front.fate == "relayed" and any(_at_edges(run, front)))


def rupture_kind(fr: list[Front], crossed: list[Front], t_slip: float | None) -> str:
    """"pulse", "crack", "mixed" or "none" (the module's definition); ``crossed`` the fronts that crossed the
    contact (``crossed_contact``), in catalogue order."""
    if crossed:
        return crossed[0].kind
    if t_slip is None:
        return "none"
    kinds = {f.kind for f in fr if f.nucleation_time <= t_slip}
    return kinds.pop() if len(kinds) == 1 else "mixed" if kinds else "none"


# Units of the observables' columns, for tables and headers.
UNITS = {"first_break_time": "l/c_r", "first_break_x": "l", "mu_first_break": "-", "mu_s": "-",
         "mu_s_time": "l/c_r", "mu_s_after_first_break": "l/c_r", "mu_s_place": "-", "mu_s_window": "-",
         "slip_onset_time": "l/c_r", "F_s": "m c^2/a", "mu_sliding": "-", "n_fronts": "-", "n_pulse": "-",
         "n_crack": "-", "n_crossed": "-", "n_precursors": "-", "n_running": "-", "n_merged": "-",
         "precursor_arrest_mean": "l",
         "precursor_arrest_max": "l", "rupture_kind": "-", "front_speed": "c_r", "front_speed_mean": "c_r",
         "slip_per_event": "l"}


def summary_lines(run, **kw) -> list[str]:
    """The friction part of a run's report: static peak, slip onset, precursors."""
    pk = static_peak(run)
    if not math.isfinite(pk.mu_s):
        return ["friction: no mu(t) in this record"]
    where = ("" if pk.place == "no break" else
             f", {abs(pk.after_first_break):.3f} l/c_r {pk.place} the first break (mu there {pk.mu_first_break:.4g})"
             if pk.place != "at" else ", at the first break")
    bound = "" if pk.window == "slip onset" else " (a lower bound: the contact never slipped everywhere)"
    lines = [f"static peak mu_s = {pk.mu_s:.4g}{bound} at t = {pk.time:.3f} l/c_r{where}"]
    lines.append(f"slip onset (every bond broken once) at t = {pk.slip_onset:.3f} l/c_r"
                 if pk.slip_onset is not None else "slip onset: not within the record")
    pre = precursors(run, **kw)
    if pre:
        lines.append(f"{len(pre)} precursors (fronts that arrested), arrest lengths "
                     + ", ".join(f"{p.arrest_length:.3f}" for p in pre[:12]) + " l")
    else:
        lines.append("no precursors (no front arrested inside the contact)")
    return lines


def summary(run) -> str:
    """First break, the front catalogue with each front's fate, and the friction record (static peak,
    slip onset, precursors), as ``parslip run`` prints it."""
    iface = run.interface
    tb, xb = first_break(iface)
    lines = []
    if tb is None:
        lines.append("no bond broke")
    else:
        lines.append(f"first break at t = {tb:.3f} l/c_r, x/l = {', '.join(f'{v:.3f}' for v in xb[:6])}")
    fr = run.fronts()
    lines.append(f"{len(fr)} rupture fronts")
    if fr:
        lines.append(table(fr[:12]))
    if "mu" in iface and len(iface["x"]):
        lines += summary_lines(run)
    return "\n".join(lines)


# The smallest drop of mu that counts as a slip event, as a share of the record's largest mu: twice the
# rebound after a slip in the push through a soft loader (drive.spring = 0.05: about 10 %), and twenty
# times the frame-to-frame jitter of mu while it slides (about 1 %).
MIN_DROP = 0.2


def slip_events(run, min_drop: float = MIN_DROP, **kw) -> list[SlipEvent]:
    """The slip events of a stick-slip record: each drop of mu(t) from a peak to the following trough by
    at least ``min_drop`` times the record's largest mu, found as a drawdown (a stick phase ends where mu
    has fallen that far below its running peak; the slip ends at the lowest mu before mu has risen that
    far again).  With each event: mu before and after, the loader's displacement at its start, the fronts
    nucleated since the previous event ended, and the precursors (fronts arrested inside the contact) since the previous event
    with their arrest lengths and mu at arrest.  An event still falling at the record's end is included."""
    iface = run.interface
    m, t = mu(run), np.asarray(iface["t"], float)
    ok = np.isfinite(m)
    if not ok.any():
        return []
    threshold = min_drop * float(np.nanmax(np.abs(m)))
    if threshold <= 0:
        return []
    spans, k_peak, k_low, slipping = [], int(np.argmax(ok)), None, False
    for k in np.flatnonzero(ok):
        if not slipping:
            if m[k] >= m[k_peak]:
                k_peak = k
            elif m[k_peak] - m[k] >= threshold:
                slipping, k_low = True, k
        elif m[k] < m[k_low]:
            k_low = k
        elif m[k] - m[k_low] >= threshold:
            spans.append((k_peak, k_low))
            slipping, k_peak = False, k
    if slipping:
        spans.append((k_peak, k_low))
    fr = run.fronts(**kw)
    pre = precursors(run, **kw)
    loader = np.asarray(iface.get("loader", np.zeros(len(t))), float)
    out, t_prev = [], -math.inf
    for i, (a, b) in enumerate(spans):
        mine = [p for p in pre if t_prev < p.arrest_time <= t[a]]
        out.append(SlipEvent(
            i, float(t[a]), float(t[b]), float(m[a]), float(m[b]), float(m[a] - m[b]), float(loader[a]),
            [j for j, f in enumerate(fr) if t_prev < f.nucleation_time <= t[b]],
            [p.index for p in mine], [float(p.arrest_length) for p in mine],
            [float(m[min(int(np.searchsorted(t, p.arrest_time)), len(m) - 1)]) for p in mine]))
        t_prev = float(t[b])
    return out


def slip_event_lines(events: list[SlipEvent], min_drop: float = MIN_DROP) -> list[str]:
    """The slip-event catalogue as a table (``parslip fronts``)."""
    if not events:
        return [f"no slip event (no drop of mu by {min_drop:.0%} of its largest value)"]
    lines = [f"{len(events)} slip events (drops of mu by at least {min_drop:.0%} of its largest value; times "
             f"exact to the frame, every output.interface_dt):",
             f"  {'#':>3} {'t_start':>8} {'t_end':>8} {'mu_before':>9} {'mu_after':>9} {'drop':>7} "
             f"{'loader':>8} {'fronts':>6} {'precursors':>10}",
             f"  {'':>3} {'l/c_r':>8} {'l/c_r':>8} {'':>9} {'':>9} {'':>7} {'l':>8} {'':>6} {'(arrest l)':>10}"]
    for e in events:
        pre = ", ".join(f"{x:.3g}" for x in e.precursor_lengths) or "-"
        lines.append(f"  {e.index + 1:>3} {e.t_start:>8.3f} {e.t_end:>8.3f} {e.mu_before:>9.4g} {e.mu_after:>9.4g} "
                     f"{e.drop:>7.3g} {e.loader:>8.4g} {len(e.fronts):>6} {pre:>10}")
    return lines


def sinking(run) -> np.ndarray:
    """Per interface frame, how far the block's interface site that has gone deepest is below its height at
    the drive's start, in a: max over sites of -(u_y(t) - u_y(0)) * l/a, with l = lattice.top_cols a (the
    sites' count when the scene does not say).  Negative when every site stands above its start.  A site
    with no bond and no contact (``interface.contact`` = 0) feels nothing from the substrate, so under F_N
    it sinks (at about F_N/(N zeta) on the block of N nodes under absolute damping); its largest value
    over the record is the test that the contact holds the block up."""
    uy = np.asarray(run.interface["uy"], float)
    if uy.ndim != 2 or not uy.size:
        return np.zeros(0)
    l_a = float(run.scene.get("lattice.top_cols") or uy.shape[1])
    return -(uy - uy[0]).min(axis=1) * l_a


def first_crossing(run, fronts: list):
    """The first of ``fronts`` (the run's catalogue) whose own tip crossed the contact (fate "crossed"), else
    the first front, else None: the front a study's row describes."""
    for f, fate in zip(fronts, run.fates()):
        if fate == "crossed":
            return f
    return fronts[0] if fronts else None


def reformations(run, t0: float = 0.0, t1: float = math.inf) -> int:
    """Bonds re-formed at t0 < t < t1 (l/c_r), counted from the event record; -1 for a run without one."""
    ev = run.events
    if ev is None:
        return -1
    t = np.asarray(ev["time"])
    return int(np.sum((np.asarray(ev["kind"]) == EVENT_FORM) & (t > t0) & (t < t1)))
