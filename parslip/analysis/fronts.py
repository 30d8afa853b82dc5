"""Rupture fronts of a run: the one detector, the catalogue, its per-front fields, and the measures of
fronts and their speeds.  Every measure is a function of the run (``parslip.open``'s object,
``analysis.results.Run``; ``Run.from_arrays`` builds one from drawn arrays); none reads a file or draws.

The detector
  fronts(run, max_gap, min_sites, window)   every rupture front, in order of nucleation (``Front``).  The tips
                                            come from the bond events (``/interface/events``: arrival times
                                            exact to dt); a file without events goes through the same code
                                            with its breaks read off the frames (arrival times to the frame)
  first_break(iface)                        (t, x) of the first bond break, from the interface record
The per-front fields
  FIELDS, front_field, declare              the registry: every field of a front, with its units and meaning,
                                            declared once where it is defined; ``parslip fronts`` (table and
                                            --json), ``Run.fronts()`` (``front.<name>``) and the field table
                                            of docs/guide/analysis.md read it
  table(fronts), resolution_lines(fronts)   the catalogue as text
Measures of fronts and speeds
  wave_speeds(run), band_of(speed, waves)   the wave speeds that class a speed, and its band (``BANDS``)
  band (per-front field)                    the band of a front's max_speed
  first_break_time(run), first_break_frame(run)       the first break, l/c_r and its frame
  driven_edge(run)                          x/l of the edge the drive loads first
  crossing_time(run, i, reach)              time a front took to run ``reach`` l, l/c_r
  peak_speed(run, i), crack_speed(run, i, past)       a front's largest local speed and its speed past ``past``
  accel_time(front)                         when a front's tip reached its ``accel_x``, l/c_r
  tip_frames(run, front)                    the frame that first shows each of a front's breaks
  section_width(run, t)                     median length of the interior broken runs at t, a

Units: x and slip in l, t in l/c_r, so speeds come out in c_r; widths in lattice spacings a (one site = one a).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..io.contract import EVENT_BREAK, EVENT_FORM

# l/c_r: the longest pause of a tip whose bond re-attached before it moved on, for its front to stay one
# front (the detector's patience); the default of every function that groups breaks into fronts.
MAX_GAP = 3.0
# The fewest bonds a front breaks to be catalogued: fewer is a flicker (a bond or a few breaking on their own).
MIN_SITES = 5
# Each local speed is fitted over 2 * WINDOW + 1 consecutive sites of the tip's path.
WINDOW = 2
ACCEL_FACTOR = 2.0      # a front "accelerates" where |v| first exceeds this multiple of its early speed


# --- the per-front fields: declared once ------------------------------------------------------------

@dataclass(frozen=True)
class FrontField:
    """One field of a catalogued front: its name (the JSON key and ``front.<name>``), units, meaning, the
    measure that computes it from (run, front) (None for what the detector itself gives) and its column
    in the text table (``col`` the header, ``fmt`` a format spec whose leading digits are the width; no
    column when ``col`` is None)."""
    name: str
    units: str
    doc: str
    measure: Callable | None = None
    col: str | None = None
    fmt: str = ""
    source: str = "analysis.fronts"


FIELDS: dict[str, FrontField] = {}
# Per-site measures other modules add to ``tip`` in the JSON (``tip_values``): name -> measure(run, front),
# which returns {key: array with one entry per site of front.tip, NaN where not measured}.
TIP_VALUES: dict[str, Callable] = {}


def declare(name: str, units: str, doc: str, col: str | None = None, fmt: str = "",
            measure: Callable | None = None) -> None:
    """Add a field to the registry (a detector field when ``measure`` is None)."""
    if name in FIELDS:
        raise ValueError(f"front field {name!r} declared twice")
    src = measure.__module__.replace("parslip.", "") if measure is not None else "analysis.fronts"
    FIELDS[name] = FrontField(name, units, doc, measure, col, fmt, src)


def tip_values(name: str):
    """Decorator: register ``measure(run, front)`` whose per-site arrays (one entry per site the tip reached,
    NaN where not measured) join ``tip`` in ``Front.to_dict`` (the --json output) under their own keys."""
    def register(measure):
        if name in TIP_VALUES:
            raise ValueError(f"tip values {name!r} registered twice")
        TIP_VALUES[name] = measure
        return measure
    return register


def front_field(name: str, units: str, doc: str, col: str | None = None, fmt: str = ""):
    """Decorator: register ``measure(run, front)`` as the per-front field ``name`` (units, a one-line
    meaning, an optional table column).  The catalogue, its JSON, ``front.<name>`` and the docs' field
    table pick it up; nothing else needs an edit."""
    def register(measure):
        declare(name, units, doc, col, fmt, measure)
        return measure
    return register


for _name, _units, _doc, _col, _fmt in (
        ("nucleation_time", "l/c_r", "t of the front's first break (exact to dt from events)", "t_nuc", "8.3f"),
        ("nucleation_x", "l", "x of the first broken site (the rearmost, along the direction, when several "
         "broke at once)", "x_nuc", "6.3f"),
        ("direction", "-", "+1 toward x/l = 1, -1 toward x/l = 0, 0 if it did not move", "dir", "+4d"),
        ("kind", "-", "pulse when a bond behind the tip had re-attached when the tip made its last advance, "
         "else crack", "kind", ">6"),
        ("mean_speed", "c_r", "(x_last - x_first) / (t_last - t_first), signed (null for a front that broke "
         "faster than every wave speed from end to end)", "v_mean", "9.3g"),
        ("max_speed", "c_r", "the fitted local speed of largest magnitude, signed, bursts included (its band "
         "says which)", "v_max", "9.3g"),
        ("steady_speed", "c_r", "|speed| fitted over the middle 60 % of the sites", None, ""),
        ("accel_x", "l", f"first x_tip where |v| exceeds {ACCEL_FACTOR:g} x the median speed of the first half "
         "of the path (null if never)", "accel_x", "7.3f"),
        ("width", "a", "median width of the broken zone behind the tip, lattice spacings", "width", "6.1f"),
        ("slip_u", "l", "median over the sites crossed of the slip u the front carries there (tip du)",
         "slip_u", "9.3g"),
        ("slip_v", "l", "the same for the vertical displacement v (tip dv)", "slip_v", "9.3g"),
        ("sites", "-", "how many sites its tip reached", "sites", "5d"),
        ("resolution", "l/c_r", "the time resolution of the arrival times: dt, or the frame interval for a "
         "file without events", None, ""),
        ("fit_sites", "-", "sites in each local speed fit (2 window + 1)", None, ""),
        ("supershear", "-", "stretches of the path whose local speed exceeds the block's c_s (and at most the "
         "fastest wave speed), each {sites: [first, last], x: [x0, x1], t: [t0, t1], n_sites, n_steps, "
         "max_speed}", None, ""),
        ("bursts", "-", "stretches whose fit exceeds every wave speed the system carries: breaks too close in "
         "time for any signal, no speed (v is null there; max_speed the largest fit); same keys as supershear",
         None, ""),
        ("stretches", "-", "the whole path cut into speed bands: each stretch as in supershear, with its band "
         "(sub-Rayleigh, c_R to c_s, supershear, above block c_l or burst)", None, ""),
        ("tip", "-", "arrays along the tip trajectory, one entry per site reached: t (arrival), step (its drive "
         "step; from events only), frame (the first frame that shows the break), x, v (local speed, NaN in a "
         "burst), w (width, a), du, dv (slip carried at that site, l), u_behind, v_behind (displacement of "
         "the site behind the tip at its arrival, from t = 0, l); in the JSON also the per-site measures other "
         "modules register (``tip_values``: analysis.cracks adds G_contour_inner, G_contour_outer, G_field and "
         "Gamma, m c_r^2/a, null where not measured)", None, "")):
    declare(_name, _units, _doc, _col, _fmt)


def json_value(v):
    """A value as JSON holds it: numpy scalars as Python numbers, NaN and infinities as None."""
    if isinstance(v, (np.floating, np.integer)):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


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

    Every registered measure (``FIELDS``, ``front_field``) reads as an attribute, ``front.fate``, computed
    from the run the front belongs to on first use.
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
    fit_sites: int = 2 * WINDOW + 1   # sites in each local speed fit
    # Stretches of the tip's path, each {"sites": [first, last], "x": [x0, x1] (l), "t": [t0, t1] (l/c_r),
    # "n_sites", "n_steps" (distinct break steps), "max_speed" (c_r, unsigned; None for a burst)}:
    supershear: list = field(default_factory=list)   # local speed above c_s (and at most c_max)
    bursts: list = field(default_factory=list)       # fits above every wave speed: not a speed
    stretches: list = field(default_factory=list)    # the path cut into speed bands, each with its "band"
    max_gap: float = MAX_GAP    # the detector's patience this front was found with, l/c_r
    run: object = field(default=None, repr=False, compare=False)   # the run it belongs to (its measures read it)

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

    def field(self, name: str):
        """The registered field ``name`` (``FIELDS``): a detector field, or its measure's value on this front
        in its run (computed once; None for a front that belongs to no run)."""
        spec = FIELDS[name]
        if spec.measure is None:
            return getattr(self, name)
        cache = self.__dict__.setdefault("_measured", {})
        if name not in cache:
            cache[name] = None if self.run is None else spec.measure(self.run, self)
        return cache[name]

    def __getattr__(self, name: str):
        spec = FIELDS.get(name) if not name.startswith("_") else None
        if spec is None or spec.measure is None:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        return self.field(name)

    def to_dict(self) -> dict:
        """JSON-ready: every registered field (``FIELDS``) under its name, NaN as None."""
        d = {}
        for name in FIELDS:
            v = self.field(name)
            if name == "tip":
                v = dict(v)
                for measure in TIP_VALUES.values():
                    v.update(measure(self.run, self) if self.run is not None else {})
                v = {k: [json_value(float(x)) for x in a] for k, a in v.items()}
            d[name] = v if isinstance(v, (list, dict)) else json_value(v)
        return d


def field_help(width: int = 78) -> str:
    """The registered per-front fields as help text: one entry per field, "name (units): meaning"."""
    import textwrap
    lines = ["", "", "Per-front fields (the --json keys; the table shows those with a column):"]
    for spec in FIELDS.values():
        units = "" if spec.units == "-" else f" ({spec.units})"
        lines += textwrap.wrap(f"{spec.name}{units}: {spec.doc}", width, initial_indent="  ",
                               subsequent_indent="      ")
    return "\n".join(lines)


def _cell(spec: FrontField, v) -> str:
    """One table cell: the value in the field's format, "-" where it is missing."""
    if isinstance(v, (np.floating, np.integer)):
        v = v.item()
    return f"{'-':>{_width(spec)}}" if v is None else format(v, spec.fmt)


def _width(spec: FrontField) -> int:
    m = re.match(r"[<>^]?[+-]?(\d+)", spec.fmt)
    return int(m.group(1)) if m else 0


def table(fr: list[Front]) -> str:
    """The catalogue as a readable table: a column for every registered field that has one (``FIELDS``),
    units in the header."""
    cols = [spec for spec in FIELDS.values() if spec.col]
    units = [("" if spec.units == "-" else spec.units) for spec in cols]
    rows = [f"{'#':>3} " + " ".join(f"{spec.col:>{_width(spec)}}" for spec in cols),
            f"{'':>3} " + " ".join(f"{u:>{_width(spec)}}" for spec, u in zip(cols, units))]
    for i, f in enumerate(fr):
        rows.append(f"{i + 1:>3} " + " ".join(_cell(spec, f.field(spec.name)) for spec in cols))
    return "\n".join(rows + resolution_lines(fr))


def resolution_lines(fr: list[Front]) -> list[str]:
    """What the catalogue's speeds are resolved to, and every stretch flagged as supershear or as a burst."""
    if not fr:
        return []
    f0 = fr[0]
    src = "exact break steps" if f0.tip.get("step") is not None else "interface frames"
    out = [f"speeds: tip arrival times from {src} (resolution {f0.resolution:.3g} l/c_r), each local speed "
           f"fitted over {f0.fit_sites} sites"]
    if f0.run is not None:
        w = wave_speeds(f0.run)
        out.append(f"bands (c_r): c_R = {w['c_R']:.4g} (the lattice's Rayleigh speed), block c_s = {w['c_s']:.4g}, "
                   f"c_l = {w['c_l']:.4g}; fastest wave carried {w['c_max']:.4g}" +
                   (" (the substrate's c_l)" if w["c_max"] > w["c_l"] else ""))
    for i, f in enumerate(fr):
        for name, items in (("supershear (above c_s)", f.supershear), ("burst (fit above every wave speed: "
                                                                      "near-simultaneous breaks, no speed)", f.bursts)):
            for b in items:
                speed = f", up to {b['max_speed']:.3g} c_r" if b.get("max_speed") is not None else ""
                out.append(f"  front {i + 1}: {name}: sites {b['sites'][0]}-{b['sites'][1]} (x/l {b['x'][0]:.3f}-"
                           f"{b['x'][1]:.3f}), t = {b['t'][0]:.4f}-{b['t'][1]:.4f} l/c_r, {b['n_sites']} sites in "
                           f"{b['n_steps']} steps{speed}")
    return out


# --- the detector ----------------------------------------------------------------------------------
# A tip reaches a site at that site's break step.  The breaks come from the bond events (exact to dt) or,
# in a file written before events existed, from the frames (each frame a "step" whose breaks are the
# bonds it first shows broken, and whose re-formations the bonds it first shows intact again).  Either
# way the same code groups them into fronts, fits their speeds and reads their slip.

def _break_record(run) -> dict:
    """The bond events the detector reads, as arrays ``step``, ``time`` (l/c_r), ``site``, ``kind``
    (EVENT_BREAK, EVENT_FORM) and ``frame`` (the first interface frame that shows each), sorted by step,
    site, kind; with ``dt`` (the resolution of the times, l/c_r) and ``exact`` (True for events, False for
    tips read off the frames)."""
    iface = run.interface
    ev = iface.get("events")
    nf = len(iface["t"])
    if ev is not None:
        steps = np.asarray(ev["step"], np.int64)
        fsteps = iface.get("step")
        frame = (np.minimum(np.searchsorted(fsteps, steps, side="right"), nf - 1) if fsteps is not None and nf
                 else np.zeros(len(steps), np.int64))
        return {"step": steps, "time": np.asarray(ev["time"], float), "site": np.asarray(ev["site"]),
                "kind": np.asarray(ev["kind"]), "frame": frame, "dt": float(ev["dt"]), "exact": True}
    broken = np.asarray(iface["intact"]) == 0
    change = broken.copy()
    change[1:] ^= broken[:-1]                  # a bond broken in frame 0 counts as broken there
    k, s = np.nonzero(change)
    t = np.asarray(iface["t"], float)
    return {"step": k.astype(np.int64), "time": t[k], "site": s,
            "kind": np.where(broken[k, s], EVENT_BREAK, EVENT_FORM), "frame": k.astype(np.int64),
            "dt": float(np.median(np.diff(t))) if nf > 1 else 1.0, "exact": False}


def wave_speeds(run) -> dict:
    """The wave speeds that class a front's speed, in c_r (``model.physics``):

      c_R     the Born lattice's own surface-wave speed (root ``c_surface_born``: 0.9475 c_s = 1.040 c_r at
              nu = 0.2), the lattice's Rayleigh speed; c_s when the run does not say
      c_s, c_l   the block's shear and longitudinal speeds (the event record's, or the root attributes')
      sub_l   the substrate's longitudinal speed, from its stiffnesses ``material.bottom_kn``,
              ``material.bottom_kt`` (Eq. 2.2 inverted: c_l^2 = (9 k_n + 3 k_t)/8 a^2); 0 for a rigid
              substrate or none
      c_max   the fastest wave the system carries, max(c_l, sub_l): a fit above it is no speed (a burst)

    A run that names none of them (a record drawn without attributes) gets inf for c_s, c_l and c_max."""
    from ..model.physics import born_wave_speeds
    a, ev, sc = run.attrs, run.events, run.scene
    c_r = float(a.get("c_r", 1.0))
    if ev is not None:
        c_s, c_l = float(ev["c_s"]), float(ev["c_l"])
    elif "c_s" in a and "c_l" in a:
        c_s, c_l = float(a["c_s"]) / c_r, float(a["c_l"]) / c_r
    else:
        c_s = c_l = math.inf
    c_R = float(a["c_surface_born"]) / c_r if "c_surface_born" in a else c_s
    sub_l = 0.0
    if sc.get("lattice.substrate", "elastic") == "elastic" and sc.get("lattice.bottom_rows", 0) and \
            "material.bottom_kn" in sc:
        sub_l = born_wave_speeds(float(sc["material.bottom_kn"]), float(sc.get("material.bottom_kt", 0.0)))[0] / c_r
    return {"c_R": c_R, "c_s": c_s, "c_l": c_l, "sub_l": sub_l, "c_max": max(c_l, sub_l)}


# The speed bands, slowest first: (name, the wave speed (``wave_speeds``) it ends at).
BANDS = (("sub-Rayleigh", "c_R"), ("c_R to c_s", "c_s"), ("supershear", "c_l"), ("above block c_l", "c_max"),
         ("burst", None))


def band_of(speed: float, waves: dict) -> str | None:
    """The band of a speed (c_r, either sign): sub-Rayleigh below c_R, "c_R to c_s", supershear from c_s to
    the block's c_l, "above block c_l" up to the fastest wave the substrate carries, burst above every wave
    speed (``BANDS``; each band holds its upper end); None for NaN."""
    v = abs(speed)
    if not math.isfinite(v):
        return None
    return next(name for name, top in BANDS if top is None or v <= waves[top])


def _runs(sites: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous runs [a, b] of a sorted array of site indices."""
    if len(sites) == 0:
        return []
    cut = np.flatnonzero(np.diff(sites) > 1)
    starts = np.r_[sites[0], sites[cut + 1]]
    ends = np.r_[sites[cut], sites[-1]]
    return list(zip(starts.tolist(), ends.tolist()))


class _Chain:
    """Sites a front has broken, with the step each broke in; it grows only at its tip."""

    def __init__(self, a: int, b: int, k: int, order: int = 0):
        self.arrival = {s: k for s in range(a, b + 1)}
        self.order = order                  # its place in the order of nucleation (ties go to the older)
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

    def ahead(self) -> tuple:
        """The sites whose break would extend it: beyond its tip, or beyond both ends while it has no direction."""
        return (self.hi + 1,) if self.d > 0 else (self.lo - 1,) if self.d < 0 else (self.hi + 1, self.lo - 1)


def _extend(lo: int, hi: int, ahead: dict, broken: np.ndarray, t_of: dict, t: float, max_gap: float):
    """The chain the run [lo, hi] of new breaks extends, and on which side: among the chains whose tip it
    covers the site beyond, the alive one (its tip bond still broken as the step began, or its last advance
    at most ``max_gap`` ago) that advanced most recently, the older of two that advanced in the same step;
    (None, 0) when there is none."""
    best, side = None, 0
    for s in range(lo, hi + 1):
        for c in ahead.get(s, ()):
            sd = c.extends(lo, hi)
            if not sd or c is best:
                continue
            tip = c.hi if sd > 0 else c.lo
            if (broken[tip] or t - t_of[c.last] <= max_gap) and (
                    best is None or (c.last, -c.order) > (best.last, -best.order)):
                best, side = c, sd
    return best, side


def chains(rec: dict, n_sites: int, max_gap: float = MAX_GAP) -> tuple[list[_Chain], dict, dict]:
    """Breaks grouped into fronts, step by step (``_break_record``'s steps).

    The sites that break in one step form contiguous runs.  A run that covers the site just beyond a
    chain's tip (hi + 1 for a chain moving toward x = 1, lo - 1 toward x = 0; either for a chain whose
    direction is not yet known) extends that chain if it is alive (``_extend``); any other run nucleates
    a new chain.  A front so extends only from its own tip: pulses that follow each other, or a new pulse
    nucleating where an older one passed, stay separate.  Returns (chains, time of each step that has
    events, {(chain id, site): broken-zone width behind the tip, in sites, when the tip reached the site}).
    """
    steps, sites, kinds, times = rec["step"], rec["site"], rec["kind"], rec["time"]
    broken = np.zeros(n_sites, bool)        # the bond state as the step began: every site bonded at first
    out: list[_Chain] = []
    t_of: dict[int, float] = {}
    widths: dict = {}
    ahead: dict[int, list] = {}            # site -> chains whose tip it is next to
    cut = np.flatnonzero(np.diff(steps)) + 1 if len(steps) else np.zeros(0, int)
    for a, b in zip(np.r_[0, cut], np.r_[cut, len(steps)]) if len(steps) else ():
        step = int(steps[a])
        t_of[step] = float(times[a])
        grown = []
        for lo, hi in _runs(np.unique(sites[a:b][kinds[a:b] == EVENT_BREAK])):
            best, side = _extend(lo, hi, ahead, broken, t_of, t_of[step], max_gap)
            if best is None:
                best = _Chain(lo, hi, step, len(out))
                out.append(best)
                added = range(lo, hi + 1)
            else:
                added = range(best.hi + 1, hi + 1) if side > 0 else range(lo, best.lo)
                for key in best.ahead():
                    lst = ahead.get(key)
                    if lst is not None and best in lst:
                        lst.remove(best)
                best.grow(side, lo, hi, step)
            for key in best.ahead():
                ahead.setdefault(key, []).append(best)
            grown.append((best, list(added)))
        for e in range(a, b):
            broken[sites[e]] = kinds[e] == EVENT_BREAK
        for c, added in grown:               # the broken zone behind the tip once the step's events are in
            w = _width_behind(broken, c)
            for s in added:
                widths[(id(c), s)] = w
    return out, t_of, widths


def _width_behind(broken: np.ndarray, c: _Chain) -> int:
    """Contiguous broken sites from the chain's tip back toward its nucleation side."""
    site, back = (c.hi, -1) if c.d >= 0 else (c.lo, 1)
    w = 0
    while 0 <= site < len(broken) and broken[site]:
        w += 1
        site += back
    return w


def _fit_speed(xs: np.ndarray, ts: np.ndarray, d: int, res: float) -> float:
    """Signed speed d / max(d * dt_arr/dx, res / span) from arrival times ``ts`` at sites ``xs``.

    The arrival times carry the quantisation of their record (dt, or the frame interval) while x is
    exact, so t is regressed on x.  Sites the tip crossed within one ``res`` only bound the speed: it is
    capped at their span per ``res``.  NaN for a single site.
    """
    span = float(np.ptp(xs))
    if span == 0:
        return math.nan
    slope = float(np.polyfit(xs, ts, 1)[0])
    return d / max(d * slope, res / span)


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


def _stretch(i: int, j: int, s, xx, tt, steps, v) -> dict:
    """Sites i..j of a path as a stretch: its sites, x, t, how many sites and distinct steps, largest |v|."""
    vv = np.abs(v[i:j + 1])
    vv = vv[np.isfinite(vv)]
    return {"sites": [int(s[i]), int(s[j])], "x": [float(xx[i]), float(xx[j])],
            "t": [float(tt[i]), float(tt[j])], "n_sites": int(j - i + 1),
            "n_steps": int(len(np.unique(steps[i:j + 1]))), "max_speed": float(vv.max()) if len(vv) else None}


def _stretches(idx, s, xx, tt, steps, v) -> list[dict]:
    """The contiguous stretches of the path where ``idx`` holds (``_stretch``)."""
    return [_stretch(i, j, s, xx, tt, steps, v) for i, j in _runs(np.flatnonzero(idx))]


def _band_stretches(fit, s, xx, tt, steps, waves: dict) -> list[dict]:
    """The path cut into stretches of one speed band each (``band_of`` of each site's fitted local speed),
    each ``_stretch`` with its "band"; sites without a fit (a front that did not move) in none."""
    labels = [band_of(v, waves) for v in fit]
    out, i = [], 0
    while i < len(labels):
        j = i
        while j + 1 < len(labels) and labels[j + 1] == labels[i]:
            j += 1
        if labels[i] is not None:
            out.append({"band": labels[i], **_stretch(i, j, s, xx, tt, steps, fit)})
        i = j + 1
    return out


def _speeds(s, xx, tt, steps, d: int, rec: dict, m: int) -> dict:
    """The speeds of one path (sites ``s`` at x ``xx`` reached at ``tt``, steps ``steps``): local ``v`` (NaN
    in a burst: a fit above every wave speed, breaks too close in time for any signal), ``mean``,
    ``vmax`` (the fit of largest magnitude, bursts included), ``steady``, ``accel``, the ``supershear``
    and ``bursts`` stretches and the path cut into speed bands, ``stretches`` (see ``Front``)."""
    n = len(s)
    if d == 0:
        return {"v": np.full(n, np.nan), "mean": math.nan, "vmax": math.nan, "steady": math.nan, "accel": None,
                "supershear": [], "bursts": [], "stretches": []}
    res, waves = rec["dt"], rec["waves"]
    c_max = waves["c_max"]
    fit = _window_speed(tt, xx, d, res, m)
    fast = np.abs(fit) > c_max
    v = np.where(fast, np.nan, fit)
    span_t = tt[-1] - tt[0]
    mean = (xx[-1] - xx[0]) / span_t if span_t > 0 else math.nan
    lo, hi = int(0.2 * n), max(int(0.8 * n), int(0.2 * n) + 2)
    steady = abs(_fit_speed(xx[lo:hi], tt[lo:hi], d, res))
    finite = np.isfinite(v)
    half = max(1, n // 2)
    early = float(np.median(np.abs(v[:half][finite[:half]]))) if finite[:half].any() else math.nan
    accel_at = np.flatnonzero(np.abs(np.nan_to_num(v)) > ACCEL_FACTOR * early) if math.isfinite(early) else []
    return {"v": v, "mean": float(mean) if abs(mean) <= c_max else math.nan,
            "vmax": float(fit[int(np.nanargmax(np.abs(fit)))]) if np.isfinite(fit).any() else math.nan,
            "steady": float(steady) if steady <= c_max else math.nan,
            "accel": float(xx[accel_at[0]]) if len(accel_at) else None,
            "supershear": _stretches(np.abs(v) > waves["c_s"], s, xx, tt, steps, v),
            "bursts": _stretches(fast, s, xx, tt, steps, fit),
            "stretches": _band_stretches(fit, s, xx, tt, steps, waves)}


def _slips(iface: dict, s: np.ndarray, frames: np.ndarray, windows: dict) -> tuple:
    """(du, dv, u_behind, v_behind) along a path, in l (see ``Front``); NaN without displacements."""
    n = len(s)
    du, dv, ub, vb = (np.full(n, np.nan) for _ in range(4))
    if "ux" in iface and "uy" in iface and len(iface["t"]):
        ux, uy = iface["ux"], iface["uy"]
        for j in range(n):
            kk, site = int(frames[j]), int(s[j])
            k_lo, k_hi = windows[site][kk]
            du[j] = ux[k_hi, site] - ux[k_lo, site]
            dv[j] = uy[k_hi, site] - uy[k_lo, site]
            behind = int(s[j - 1]) if j else site
            ub[j] = ux[kk, behind] - ux[0, behind]
            vb[j] = uy[kk, behind] - uy[0, behind]
    return du, dv, ub, vb


def _median(a: np.ndarray) -> float:
    a = a[np.isfinite(a)]
    return float(np.median(a)) if len(a) else math.nan


def _front(c: _Chain, rec: dict, iface: dict, h: int, t_of: dict, widths: dict, windows: dict) -> Front:
    """One front from its chain of arrival steps (see ``Front``)."""
    d = c.d
    s = np.array(sorted(c.arrival, reverse=(d < 0)))
    steps = np.array([c.arrival[i] for i in s])
    frames = np.array([c.frame_of[int(i)] for i in s], np.int64)
    tt, xx = np.array([t_of[k] for k in steps]), np.asarray(iface["x"])[s]
    sp = _speeds(s, xx, tt, steps, d, rec, 2 * h + 1)
    w = np.array([widths.get((id(c), int(i)), 1) for i in s], float)
    kind = "pulse" if len(s) > 1 and w[-1] < len(s) else "crack"
    du, dv, ub, vb = _slips(iface, s, frames, windows)
    tip = {"t": tt.astype(float), "x": xx.astype(float), "v": sp["v"], "w": w, "du": du, "dv": dv,
           "u_behind": ub, "v_behind": vb}
    if rec["exact"]:
        tip["step"] = steps.astype(np.int64)
    tip["frame"] = frames
    return Front(float(tt[0]), float(xx[0]), int(d), kind, sp["mean"], sp["vmax"], sp["steady"], sp["accel"],
                 _median(w), _median(du), _median(dv), tip, resolution=float(rec["dt"]), fit_sites=2 * h + 1,
                 supershear=sp["supershear"], bursts=sp["bursts"], stretches=sp["stretches"])


def _slip_windows(arrivals: list[dict], nf: int) -> dict:
    """site -> {arrival frame: (k_lo, k_hi)}: the frames that bracket each front's passage of a site.

    ``arrivals`` holds, per front, {site: the frame that first shows its break}.  The slip a front carries
    at a site is the displacement between the midpoints (in frames) to the neighbouring fronts' arrivals
    there: frame 0 before the first front, the last frame after the last.  The fronts so share out all
    the motion of a site, creep included (which the paper finds absent between pulses), and their slips
    add up to its total displacement.
    """
    per_site: dict[int, list[int]] = {}
    for arr in arrivals:
        for site, k in arr.items():
            per_site.setdefault(site, []).append(k)
    out = {}
    for site, ks in per_site.items():
        ks = sorted(ks)
        bounds = [0] + [(a + b) // 2 for a, b in zip(ks, ks[1:])] + [nf - 1]
        out[site] = {k: (bounds[i], bounds[i + 1]) for i, k in enumerate(ks)}
    return out


def fronts(run, max_gap: float = MAX_GAP, min_sites: int = MIN_SITES, window: int = WINDOW) -> list[Front]:
    """Every rupture front of the run that broke at least ``min_sites`` bonds, in order of nucleation.

    ``max_gap`` (l/c_r): longest pause of a tip whose bond re-attached before it advanced again;
    ``window``: the local speed is fitted over 2 * window + 1 sites.  The breaks come from the bond events
    (every file written since they exist: tips exact to dt) or, for an older file, from the frames (tips
    to the frame interval), through the same chains, fits and fates (``_break_record``).  A fit above the
    block's c_l is no speed: the sites broke too close in time for any signal to have run between them (a
    burst of near-simultaneous breaks); it is reported in ``Front.bursts`` and left out of every speed.
    Local speeds above c_s are reported in ``Front.supershear``.  The slip and the displacement behind the
    tip are read off the frames (the first frame that shows the break).
    """
    iface = run.interface
    rec = _break_record(run)
    rec["waves"] = wave_speeds(run)
    found, t_of, widths = chains(rec, len(iface["x"]), max_gap)
    kept = [c for c in found if len(c.arrival) >= min_sites]
    frame_of = dict(zip(rec["step"].tolist(), rec["frame"].tolist()))
    for c in kept:
        c.frame_of = {i: frame_of[k] for i, k in c.arrival.items()}
    nf = len(iface["t"])
    windows = _slip_windows([c.frame_of for c in kept], nf) if nf else {}
    out = [_front(c, rec, iface, window, t_of, widths, windows) for c in kept]
    for f in out:
        f.max_gap, f.run = max_gap, run
    out.sort(key=lambda f: (f.nucleation_time, f.nucleation_x))
    return out


# --- measures of fronts and their speeds --------------------------------------------------------------

def first_break_time(run) -> float:
    """Time of the first bond break (``first_break``), l/c_r; NaN if no bond broke."""
    t, _ = first_break(run.interface)
    return math.nan if t is None else t


def first_break_frame(run) -> int | None:
    """The first interface frame that shows a broken bond; None if none does."""
    k = np.flatnonzero((run.interface["intact"] == 0).any(axis=1))
    return int(k[0]) if len(k) else None


def driven_edge(run) -> float:
    """x/l of the edge a run's drive loads first: 1 for pull, else 0."""
    return 1.0 if run.mode == "pull" else 0.0


def _nth(run, i: int):
    fr = run.fronts()
    return fr[i] if len(fr) > i else None


def crossing_time(run, front_index: int = 0, reach: float = 0.95) -> float:
    """Time (l/c_r) a front takes from its nucleation to a tip ``reach`` l from its start across the
    contact (the far edge for reach ~ 1); NaN if it never got there."""
    f = _nth(run, front_index)
    if f is None:
        return math.nan
    j = np.flatnonzero(np.abs(f.tip["x"] - f.nucleation_x) >= reach - 1e-9)
    return float(f.tip["t"][j[0]] - f.nucleation_time) if len(j) else math.nan


def peak_speed(run, front_index: int = 0) -> float:
    """Largest local |v|/c_r of a front (fits over the catalogue's window)."""
    f = _nth(run, front_index)
    return math.nan if f is None else float(np.nanmax(np.abs(f.tip["v"])))


def crack_speed(run, front_index: int = 0, past: float = 0.2) -> float:
    """Median |v|/c_r of a front once its tip is more than ``past`` l from its nucleation site (a burst's
    sites, which carry no speed, left out)."""
    f = _nth(run, front_index)
    if f is None:
        return math.nan
    v = np.abs(f.tip["v"][np.abs(f.tip["x"] - f.nucleation_x) > past])
    v = v[np.isfinite(v)]
    return float(np.median(v)) if len(v) else math.nan


def accel_time(front: Front) -> float:
    """t (l/c_r) at which a front's tip reached ``accel_x``; NaN if it never accelerated."""
    if front.accel_x is None:
        return math.nan
    j = np.flatnonzero(front.tip["x"] == front.accel_x)
    return float(front.tip["t"][j[0]]) if len(j) else math.nan


def tip_frames(run, front: Front) -> np.ndarray:
    """The frame that first shows each of the front's breaks: ``tip["frame"]``, or for a front built
    without it the frame nearest each arrival time."""
    if "frame" in front.tip:
        return np.asarray(front.tip["frame"], np.int64)
    return np.array([run.frame_at(t) for t in front.tip["t"]], np.int64)


def section_width(run, t: float) -> float:
    """Median length, in lattice spacings a, of the interior runs of broken bonds in the frame nearest ``t``
    (a pulse width read as a constant-time section of the space-time map).  Runs that touch either edge of
    the contact are left out.  NaN when the frame has no interior run."""
    broken = (run.interface["intact"][run.frame_at(t)] == 0).astype(np.int8)
    flips = np.flatnonzero(np.diff(np.r_[0, broken, 0]))
    lengths = [b - a for a, b in zip(flips[::2], flips[1::2]) if a > 0 and b < len(broken)]
    return float(np.median(lengths)) if lengths else math.nan


@front_field("band", "-", "the speed band of max_speed: sub-Rayleigh (below the lattice's Rayleigh speed c_R), "
             "c_R to c_s, supershear (c_s to the block's c_l), above block c_l (carried by the substrate) or burst "
             "(above every wave speed); null for a front that did not move", "band", ">15")
def band(run, front: Front) -> str | None:
    """``band_of`` the front's max_speed, with the run's wave speeds (``wave_speeds``)."""
    return band_of(front.max_speed, wave_speeds(run))
