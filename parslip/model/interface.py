"""The interface law: what an adhesive bond is, built once from the scene; everything else asks it.

A bond joins a top interface site (the block's bottom row) to a bottom site
(the substrate's top row).  With x_ij, y_ij the bond's components (top minus
bottom, in a) and x0 its rest offset:

    force on the top node:  f_x = -k_x (x_ij - x0),   f_y = -k_y (y_ij - delta0)      (m c^2/a)
    breaks when             sqrt(x_ij^2 + y_ij^2) >= delta_b                          (a)
    a free site re-bonds    to a free bottom site within ``rebond_length`` (a)

Slip weakening (``softening`` = D_c > 0, a per-site value; 0, the paper: the
bond breaks at its peak).  With s = x_ij - x0 the shear stretch, the peak is
the step at which the length test above first holds; from there the bond
weakens instead of breaking:

    peak      s_p = |s| at the peak; tau_p = k_x s_p (the shear force it held then, m c^2/a)
    slip      delta = |s| - s_p past the peak, its largest so far delta_m (irreversible)
    residual  tau_r = mu N, N = max(0, k_y (delta0 - y_ij)) the bond's normal force now (contact
              friction mu, below); 0 without it; at most tau_p
    envelope  tau_m = tau_p - (tau_p - tau_r) w,  w = min(1, delta_m / D_c)
    force     f_x = -k_d s,  k_d = tau_m / (s_p + delta_m)   (the secant to the origin: unloading and
              reloading below the envelope are elastic with k_d, damage only grows on it)
    breaks    when w = 1 (the traction has fallen to tau_r), or when its length reaches delta_b + D_c
              (a bond opening, or loaded the other way: a length the halo still serves)

k_y is untouched while the bond weakens (f_y as above, both in compression and tension), so its
normal energy is elastic and released at the break, never part of the weakening.  A re-formed bond
starts undamaged.  In a monotonic shear at a constant gap y (x0 = 0) the bond peaks at x_b =
sqrt(delta_b^2 - y^2), tau_p = k_x x_b, and its fracture energy (``fracture``)

    Gamma = tau_p x_b / 2 + (tau_p - tau_r) D_c / 2                       (m c^2/a per bond)

is its elastic energy at the peak, which the damage takes, and the weakening's area above the residual;
at D_c = 0 it is the stored energy at the break, the paper's law.  The nucleation (``Nucleation``)
forces the same weakening on a zone of sites: w = max(delta_m / D_c, the forcing's share of its time).

The rules a scene can choose are codes, each written once as an inlined
function in ``engine.kernels.interface``:

    reform   REFORM_ZERO: a re-formed bond starts with x0 = 0 (as the initial bonds);
             REFORM_CURRENT: with x0 = x_ij (unstressed in x)
    rebond   REBOND_NEAREST: the nearest free bottom site within reach; REBOND_FACING: only the one
             facing the site (its nearest column)
    heal     bits: HEAL_SPEED, a free site takes its claim only while its x-velocity relative to the
             claimed bottom site, (u(n) - u(n-1))/dt of each, is below heal_speed (Baumberger, Caroli
             & Ronsin 2002: pulses re-stick below a slip velocity V_c); HEAL_TIME, only once the same
             bottom site has been its claim (nearest free site within reach) for heal_time: the clock
             restarts from zero whenever the claim changes or lapses (the site leaves reach, or another
             site takes the bottom site first).  0: at once (the paper)

Contact (``contact`` = k_c > 0; 0, the paper: none).  A top site with no bond
(after this step's breaks and re-formations) is kept off the substrate by a
frictionless one-sided spring.  The substrate's surface under it is the
segment between the two substrate interface sites whose current x bracket
the site's current x (q + u_x,q <= x < q + 1 + u_x,q+1; none beyond the
substrate's ends).  With e = p_(q+1) - p_q the segment, n = (-e_y, e_x)/|e|
its upward normal, r = p_top - p_q and w = r.e/|e|^2 (clipped to [0, 1]):

    d = r . n                        the site's height above the surface (a); at rest d = delta0
    f = k_c (delta0 - d) n           on the top node while d < delta0, else 0 (m c^2/a)
    -(1 - w) f, -w f                 on the substrate sites q, q + 1

so momentum is conserved; the force is normal to the surface.

Contact friction (``friction`` = mu > 0, needs the contact).  A site in contact also carries a shear force of
at most mu times its normal force k_c (delta0 - d), against its slip along the surface, through a stick
spring of the contact's stiffness k_c along the segment's tangent t = (n_y, -n_x) (a penalty, as the
contact's own normal spring is; Cundall & Strack's contact, the return mapping of computational contact
mechanics).  With xi = t . (r - w e) the site's place along the surface (affine in the three nodes'
displacements, t and w of this step) and dxi its change over the step,

    e = clip(e_prev + dxi, -mu (delta0 - d), mu (delta0 - d))      the spring's stretch (a; row ``stick``)
    f = -k_c e t                     on the top node, and -(1 - w) f, -w f on the substrate sites q, q + 1

so a site slipping steadily carries mu k_c (delta0 - d) against its slip at every step (the stretch stays at
its bound: no sign flips), and one loaded below it sticks (its spring holds it, stretched less than mu
(delta0 - d): no creep).  The stretch is 0 while the site has no contact; where a bond breaks it starts at
the bond's shear force k (x_ij - x0)/k_c, so that a weakened bond, at its residual mu k_y (delta0 - y_ij),
hands over to friction without a jump when k_c = k_y.  k_c enters omega_max in the place of k_x when it is
larger (``shear_stiffness``).
On a rigid substrate the surface is the flat line delta0 below the rest
height of the block's bottom row.  A contact acts over at most 1 a + the
substrate's drift, within one ``layout.Reach.link``: the halo that serves the
bonds serves it.  k_c enters omega_max as a normal bond would
(``normal_stiffness``): a site is bonded or in contact, never both.

The per-site bond state is one table of named rows (``BOND_TABLE``) that the
loop, the halo exchange, the checkpoint and the output share: each row says
whether it travels with the halo exchange, how a checkpoint stores it and
whether the output writes it, and everything else is derived from the table
(``BONDS``).  A new field of state is one more line in the table.

Each site may have its own k_x, k_y, delta_b and softening (delta0 stays uniform):
``site_values`` starts from the scene's values, applies the seeded random
field (``interface.random.*``), then the patches (``interface.patch``, later
ones over earlier ones).  Site s stands at x = (s + 1/2)/N in l and belongs to
a patch x = [from, to) when from <= x < to.  The random field is lognormal
and so keeps its values positive (k_x, k_y) or above delta0 (delta_b, whose
excess over delta0 is the lognormal part):

    g      white noise from numpy's PCG64(seed), one value per site of the whole contact (the same
           on every rank), smoothed by a Gaussian of standard deviation correlation/sqrt(2) sites, so
           that its correlation is exp(-r^2 / (2 correlation^2)) (r, correlation in a); then
           standardised over the contact to mean 0 and standard deviation 1 exactly
    L      exp(s g - s^2/2) with s^2 = ln(1 + cv'^2): mean about 1, coefficient of variation about cv'
    value  k L with cv' = cv for kx, ky, softening; delta0 + (delta_b - delta0) L with cv' = cv delta_b/
           (delta_b - delta0) for delta_b, so that delta_b's own coefficient of variation is about cv

The field is not rescaled afterwards: its mean and cv over a contact are the
sample's (within a few per cent of the targets for 100 sites and a
correlation of a few a).

A correlation longer than ``LONGEST_CORRELATION`` = 10 contact lengths (10 N
a over N sites) is taken as 10 contact lengths: the kernel, the noise and the
work stay within about 60 N values and 60 N^2 operations whatever is asked,
and every longer correlation gives the same field as 10 N a.  Over the
contact such a field is smooth, its g a low polynomial in x: for most seeds
within a few per cent of the straight ramp g = +-sqrt(3) (2x - 1) (x in l),
its sign set by the seed, which is the limit of the standardised field as
the correlation grows without bound; for 100 sites the rms distance of g from
that ramp has median 0.026 and 90th percentile 0.14 over seeds 0-299, the rest
bowed where the sample's slope happens to be small.  L is then an exponential
ramp, exp(+-s sqrt(3) (2x - 1) - s^2/2), whose mean and cv are as above.

Units: lengths in a, stiffnesses in m c^2/a^2.
"""
from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass

import numpy as np

REFORM_ZERO, REFORM_CURRENT = 0, 1
REBOND_NEAREST, REBOND_FACING = 0, 1
REFORM_CODES = {"zero": REFORM_ZERO, "current": REFORM_CURRENT}
REBOND_CODES = {"nearest": REBOND_NEAREST, "facing": REBOND_FACING}
HEAL_SPEED, HEAL_TIME = 1, 2

# The per-site bond state: one row per field, each row one value per top interface site, all rows in the
# state's float type (integers are exact below 2^24 even in float32).  The table below is the one place a
# row is described; the row indices, what travels with the halo exchange, what a checkpoint holds and in
# which dtype, and what the output writes are all derived from it.  A row
#   travels      changes as the run goes, so the exchange sends it for every HALO site each step; a row
#                that does not travel is a site's own constant, which every rank computes for the sites it
#                stores from their global index (``InterfaceLaw.site_values``)
#   checkpoint   the dtype a checkpoint stores it in ("int64"; None: the state's float type), or False
#   output       "frame": written per interface frame (/interface/<name>, by ``kernels.interface.record``);
#                "site": written once per site (/interface/<name>, from ``site_values``); None: not written
#   initial      the value a checkpoint that lacks the row (one written before the row existed) restarts
#                with, in the row's units: what gives the behaviour of the code that wrote it (a state row's
#                fresh value; for a site's constant, the value its key had then, ``io.checkpoint.IMPLIED``).
#                None: set by the state from the scene, and every checkpoint holds it.
BondRow = namedtuple("BondRow", "name travels checkpoint output units meaning initial", defaults=(None,))
BOND_TABLE = (
    BondRow("partner", True, "int64", "frame", "-", "the substrate column bonded to (-1 broken)"),
    BondRow("x0", True, None, None, "a", "the bond's rest offset", 0.0),
    BondRow("cand", True, "int64", None, "-", "HEAL_TIME: the bottom site the free site has claimed "
                                              "(substrate column), while clock > 0", 0),
    BondRow("clock", True, "int64", None, "steps", "HEAL_TIME: consecutive steps it has claimed cand "
                                                   "(0: none; at most n_heal + 1)", 0),
    BondRow("kx", False, None, "site", "m c^2/a^2", "the bond's shear stiffness"),
    BondRow("ky", False, None, "site", "m c^2/a^2", "the bond's normal stiffness"),
    BondRow("delta_b", False, None, "site", "a", "the bond's breaking length"),
    BondRow("softening", False, None, "site", "a", "the bond's weakening distance D_c past its peak (0: it "
                                                   "breaks at its peak)", 0.0),
    BondRow("peak", True, None, None, "a", "softening: |x_ij - x0| at the bond's peak, where its weakening "
                                           "began (0: undamaged)", 0.0),
    BondRow("slipped", True, None, None, "a", "softening: the largest slip past the peak so far, |x_ij - x0| "
                                              "- peak", 0.0),
    BondRow("spent", True, None, None, "m c^2", "softening: the energy the bond's weakening has taken so far", 0.0),
    BondRow("stick", True, None, None, "a", "contact friction: the stretch of a free site's stick spring along "
                                           "the surface (0: none)", 0.0),
)
# What the table implies (``bond_layout``): names (row order), travel (indices of the travelling rows),
# checkpoint (names a checkpoint holds), dtypes ({name: checkpoint dtype}), frame_output and site_output
# (names written per frame and per site).
BondLayout = namedtuple("BondLayout", "names travel checkpoint dtypes frame_output site_output")


def bond_layout(table) -> BondLayout:
    """The row layout a bond table implies (see ``BOND_TABLE``)."""
    return BondLayout(names=tuple(r.name for r in table),
                      travel=tuple(i for i, r in enumerate(table) if r.travels),
                      checkpoint=tuple(r.name for r in table if r.checkpoint is not False),
                      dtypes={r.name: r.checkpoint for r in table if r.checkpoint is not False},
                      frame_output=tuple(r.name for r in table if r.output == "frame"),
                      site_output=tuple(r.name for r in table if r.output == "site"))


BONDS = bond_layout(BOND_TABLE)
BOND_ROWS = BONDS.names
# The rows the compiled kernels index by name.
PARTNER, X0, CAND, CLOCK, KX, KY, DELTA_B, SOFTENING, PEAK, SLIPPED, SPENT, STICK = (
    BOND_ROWS.index(name) for name in ("partner", "x0", "cand", "clock", "kx", "ky", "delta_b", "softening", "peak",
                                       "slipped", "spent", "stick"))

# Kinds of a bond event (``/interface/events/kind``): the one place they are numbered.
BREAK, FORM = 1, 2
EVENT_KINDS = {BREAK: "break", FORM: "re-formation"}

# What the compiled update reads of the law besides the per-site rows, lengths in the state's float type:
#   delta0 (a), rebond_length (a), reform, rebond and heal: the rules' codes; heal_du = heal_speed dt (a):
#   the largest relative x-displacement per step at which a site re-bonds; n_heal = ceil(heal_time/dt).
#   contact (m c^2/a^2): the stiffness of the unbonded sites' contact with the substrate (0: none).
#   soften: SOFTEN when some bond weakens (a site's D_c > 0, or a nucleation), else 0 (the paper's break);
#   mu: the contact's friction coefficient, which sets the weakening's residual; tiny: the smallest positive
#   normal number of the float type (the peak of a bond that peaks with no shear stretch).
#   nuc: the nucleation's code (NUCLEATE_*, 0 none); nuc_lo, nuc_hi: its global sites [lo, hi);
#   nuc_centre: the zone's centre in sites (site s stands at s + 1/2); nuc_delay: steps per site the forced
#   front takes (0: every site at once); nuc_steps: the steps a site's forcing takes to the residual;
#   nuc_start: the step the forcing starts (NEVER until decided: ``engine.simulation`` sets it once a held
#   prestress has settled).
Rules = namedtuple("Rules", "delta0 rebond_length reform rebond heal heal_du n_heal contact soften mu tiny nuc "
                            "nuc_lo nuc_hi nuc_centre nuc_delay nuc_steps nuc_start")
SOFTEN = 1
NUCLEATE_TIME, NUCLEATE_FORCED = 1, 2
NUCLEATION_CODES = {"none": 0, "time": NUCLEATE_TIME, "forced": NUCLEATE_FORCED}
# A step no run reaches: the nucleation's start before it is decided.
NEVER = 2 ** 62


PATCH_KEYS = ("kx", "ky", "delta_b", "softening")
RANDOM_KEYS = ("kx", "ky", "delta_b", "softening")


def check_patches(patches, delta0: float) -> None:
    """Refuse, with one line naming the reason, a patch list a scene cannot mean (ConfigError)."""
    from ..errors import ConfigError
    if not isinstance(patches, list):
        raise ConfigError(f"interface.patch = {patches!r}: accepted: an array of tables [[interface.patch]], each "
                          f"with x = [from, to] in l and any of {', '.join(PATCH_KEYS)}")
    for i, p in enumerate(patches):
        where = f"interface.patch[{i}]"
        if not isinstance(p, dict):
            raise ConfigError(f"{where} = {p!r}: accepted: a table with x = [from, to] and any of "
                              f"{', '.join(PATCH_KEYS)}")
        extra = sorted(set(p) - {"x", *PATCH_KEYS})
        if extra:
            raise ConfigError(f"{where}.{extra[0]} = {p[extra[0]]!r}: a patch sets only {', '.join(PATCH_KEYS)} "
                              f"(delta0 stays uniform); accepted keys: x, {', '.join(PATCH_KEYS)}")
        x = p.get("x")
        if not (isinstance(x, list) and len(x) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                            for v in x)):
            raise ConfigError(f"{where}.x = {x!r}: accepted: [from, to] in l, 0 <= from < to <= 1")
        if not 0.0 <= x[0] < x[1] <= 1.0:
            why = "reversed or empty" if x[0] >= x[1] else "outside the contact [0, 1]"
            raise ConfigError(f"{where}.x = {x!r}: {why}; accepted: [from, to] in l, 0 <= from < to <= 1")
        for key, ok, acc in (("kx", lambda v: v >= 0, ">= 0"), ("ky", lambda v: v > 0, "> 0"),
                             ("delta_b", lambda v: v > delta0, f"> delta0 = {delta0!r}"),
                             ("softening", lambda v: v >= 0, ">= 0 (in a)")):
            if key in p:
                v = p[key]
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not ok(v) or v != v:
                    why = "at or below delta0" if key == "delta_b" and isinstance(v, (int, float)) else "out of range"
                    raise ConfigError(f"{where}.{key} = {v!r}: {why}; accepted: {acc}")


LONGEST_CORRELATION = 10.0      # contact lengths: a longer correlation is smoothed as this one (module docstring)


def random_field(n: int, cv: float, correlation: float, seed: int) -> np.ndarray:
    """The lognormal factor L of the module docstring over n sites: mean about 1, coefficient of variation
    about ``cv``, correlation length ``correlation`` (a), taken as at most ``LONGEST_CORRELATION`` n a so
    that its kernel stays within a few contact lengths; the same for a seed on every rank and every host.

    Portable: the smoothing is a sum over the kernel's taps in a fixed order (not np.convolve, a BLAS
    dot whose kernel OpenBLAS picks per CPU), the sums of the kernel, mean and variance are math.fsum
    (exact), and exp and log1p are libm's scalar ones (NumPy's vector exp differs in the last bit
    between CPUs)."""
    if cv == 0 or n == 0:
        return np.ones(n)
    rng = np.random.Generator(np.random.PCG64(seed))
    s = min(correlation, LONGEST_CORRELATION * n) / math.sqrt(2.0)    # kernel width, sites
    pad = int(math.ceil(4 * s))
    w = rng.standard_normal(n + 2 * pad)
    if s > 0:
        kernel = [math.exp(-0.5 * (k / s) * (k / s)) for k in range(-pad, pad + 1)]
        total = math.fsum(kernel)
        smooth = np.zeros(n)
        for j, kj in enumerate(kernel):             # symmetric: the same as a convolution
            smooth += (kj / total) * w[j:j + n]
        w = smooth
    else:
        w = w[pad:pad + n]
    mean = math.fsum(w.tolist()) / n
    dev = w - mean
    std = math.sqrt(math.fsum((dev * dev).tolist()) / n)
    g = dev / std if n > 1 and std > 0 else np.zeros(n)
    s2 = math.log1p(cv * cv)
    return np.array([math.exp(x) for x in (math.sqrt(s2) * g - 0.5 * s2).tolist()])


def site_x(n_sites: int) -> np.ndarray:
    """Where each of the n_sites interface sites stands along the contact (l): site s at (s + 1/2)/N."""
    return (np.arange(n_sites) + 0.5) / max(n_sites, 1)


def zone_sites(x, n_sites: int) -> tuple[int, int]:
    """The global sites [lo, hi) of a stretch x = (from, to) of the contact (l): those with from <= x_s < to, as
    a patch takes them (``site_x``); lo = hi when it holds none."""
    inside = np.flatnonzero((site_x(n_sites) >= x[0]) & (site_x(n_sites) < x[1]))
    return (int(inside[0]), int(inside[-1]) + 1) if len(inside) else (0, 0)


@dataclass(frozen=True)
class Nucleation:
    """A rupture started in the contact (``interface.nucleation``; Andrews 1976, Bizzarri 2010): from ``start``
    (l/c_r after the held prestress has settled, or after the drive's start without one), the bonds of the zone
    x = [from, to) (l) weaken to their residual whatever their slip:

      "time"    every site of the zone at once, its weakening share w rising linearly to 1 over ``duration``
      "forced"  a front from the zone's centre grows both ways at ``speed`` (c_r) to its ends; each site it
                reaches weakens as above over ``duration`` (0: at once), then the zone is left free

    A site's forcing ends when its share reaches 1 (its bond breaks there, if it had one): a bond that
    re-forms later is free.  Times in l/c_r, x in l, speed in c_r."""
    kind: str                    # "time" or "forced"
    x: tuple                     # (from, to) in l
    duration: float = 0.0        # l/c_r: a site's forcing, from its start to its residual
    speed: float = 0.0           # c_r: the forced front's speed ("forced")
    start: float = 0.0           # l/c_r after the prestress settled (or after the drive's start)

    KEYS = ("kind", "x", "duration", "speed", "start")

    @classmethod
    def from_scene(cls, scene: dict) -> "Nucleation | None":
        kind = scene["interface.nucleation.kind"]
        if kind == "none":
            return None
        return cls(kind=kind, x=tuple(float(v) for v in scene["interface.nucleation.x"]),
                   duration=float(scene["interface.nucleation.duration"]),
                   speed=float(scene["interface.nucleation.speed"]), start=float(scene["interface.nucleation.start"]))

    def sites(self, n_sites: int) -> tuple[int, int]:
        """The zone's global sites [lo, hi) (``zone_sites``)."""
        return zone_sites(self.x, n_sites)


def check_nucleation(scene: dict) -> None:
    """Refuse, with one line naming the key, the value and what is accepted (ConfigError), a nucleation that
    cannot start a rupture in the contact."""
    from ..errors import ConfigError
    kind = scene["interface.nucleation.kind"]
    x = scene["interface.nucleation.x"]
    if kind == "none":
        return
    ok_x = (isinstance(x, list) and len(x) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                        for v in x))
    if not ok_x or not 0.0 <= x[0] < x[1] <= 1.0:
        why = ("not [from, to]" if not ok_x else "reversed or empty" if x[0] >= x[1]
               else "outside the contact [0, 1]")
        raise ConfigError(f"interface.nucleation.x = {x!r}: {why}; accepted: [from, to] in l, 0 <= from < to <= 1 "
                          f"(the zone of the contact the nucleation weakens)")
    n = scene["lattice.top_cols"]
    lo, hi = Nucleation(kind, tuple(x)).sites(n)
    if hi <= lo:
        raise ConfigError(f"interface.nucleation.x = {x!r}: holds no interface site (site s stands at (s + 1/2)/"
                          f"{n} l); accepted: a zone [from, to] that holds at least one")
    if scene["lattice.bottom_rows"] == 0:
        raise ConfigError(f"interface.nucleation.kind = {kind!r}: a free block (lattice.bottom_rows = 0) has no "
                          f"contact; accepted: 'none' without a substrate")
    if kind == "forced" and not scene["interface.nucleation.speed"] > 0:
        raise ConfigError(f"interface.nucleation.speed = {scene['interface.nucleation.speed']!r}: a forced "
                          f"nucleation grows at this speed; accepted: > 0 (in c_r) with kind = 'forced'")


@dataclass(frozen=True)
class InterfaceLaw:
    """The adhesive bonds of one scene (see the module docstring); lengths in a, stiffnesses in m c^2/a^2."""
    delta0: float                # unloaded gap; the rest length of y_ij
    delta_b: float               # breaking length
    kx: float                    # shear stiffness
    ky: float                    # normal stiffness
    reform: int                  # REFORM_* code
    rebond: int                  # REBOND_* code
    rebond_length: float         # largest length at which a free site re-bonds (delta0 unless set)
    heal_speed: float = 0.0      # c_r: re-bond only below this relative slip velocity (0: no condition)
    heal_time: float = 0.0       # l/c_r: re-bond only after claiming the same site this long (0: at once)
    patches: tuple = ()          # ((from, to), {"kx"|"ky"|"delta_b": value}) in order
    random: tuple = ()           # (key, cv, correlation in a, seed), or () for none
    contact: float = 0.0         # m c^2/a^2: an unbonded site's contact stiffness (0: none, the paper)
    softening: float = 0.0       # a: D_c, the weakening distance past the peak (0: the paper's break)
    friction: float = 0.0        # mu, the contact's friction coefficient (0: none)
    nucleation: Nucleation | None = None

    @classmethod
    def from_scene(cls, scene: dict) -> "InterfaceLaw":
        """The law of a resolved scene (every ``interface.*`` key present)."""
        within = scene["interface.rebond_within"]
        return cls(delta0=float(scene["interface.delta0"]), delta_b=float(scene["interface.delta_b"]),
                   kx=float(scene["interface.kx"]), ky=float(scene["interface.ky"]),
                   reform=REFORM_CODES[scene["interface.reform_x0"]], rebond=REBOND_CODES[scene["interface.rebond"]],
                   rebond_length=float(within if within > 0 else scene["interface.delta0"]),
                   heal_speed=float(scene["interface.heal_speed"]), heal_time=float(scene["interface.heal_time"]),
                   patches=tuple((tuple(float(v) for v in p["x"]), tuple((k, float(p[k])) for k in PATCH_KEYS if k in p))
                                 for p in scene["interface.patch"]),
                   random=((scene["interface.random.key"], float(scene["interface.random.cv"]),
                            float(scene["interface.random.correlation"]), int(scene["interface.random.seed"]))
                           if scene["interface.random.cv"] > 0 else ()),
                   contact=float(scene["interface.contact"]), softening=float(scene["interface.softening"]),
                   friction=float(scene["interface.contact_friction"]), nucleation=Nucleation.from_scene(scene))

    @property
    def uniform(self) -> bool:
        """Every site has the scene's kx, ky and delta_b."""
        return not self.patches and not self.random

    @property
    def heal(self) -> int:
        """The healing rule's bits (HEAL_SPEED, HEAL_TIME); 0 re-bonds at once."""
        return (HEAL_SPEED if self.heal_speed > 0 else 0) | (HEAL_TIME if self.heal_time > 0 else 0)

    @property
    def soften(self) -> int:
        """SOFTEN when some bond may weaken (a site's D_c > 0 or a nucleation), else 0 (the paper's break)."""
        return SOFTEN if self.nucleation is not None or self.softening > 0 or any(
            dict(values).get("softening", 0) > 0 for _, values in self.patches) else 0

    def rules(self, dtype, setup) -> Rules:
        """The scalars the compiled update reads, lengths in the float type ``dtype``; ``setup`` gives the
        time step (a/c), the velocity unit c_r, the time unit l/c_r, the sites, and whether the drive holds a
        prestress (``scene.derive.Setup``)."""
        f = np.dtype(dtype).type
        nuc = dict(nuc=0, nuc_lo=0, nuc_hi=0, nuc_centre=0.0, nuc_delay=0.0, nuc_steps=0, nuc_start=NEVER)
        z = self.nucleation
        if z is not None:
            n = setup.lattice.n_top_sites
            lo, hi = z.sites(n)
            steps = setup.t_unit / setup.dt              # per l/c_r
            nuc.update(nuc=NUCLEATION_CODES[z.kind], nuc_lo=lo, nuc_hi=hi, nuc_centre=0.5 * (z.x[0] + z.x[1]) * n,
                       nuc_delay=(1.0 / (z.speed * setup.material.c_r * setup.dt) if z.kind == "forced" else 0.0),
                       nuc_steps=int(round(z.duration * steps)),
                       nuc_start=NEVER if setup.drive.prestress else setup.n_drive_start + int(round(z.start * steps)))
        return Rules(delta0=f(self.delta0), rebond_length=f(self.rebond_length), reform=self.reform,
                     rebond=self.rebond, heal=self.heal, heal_du=f(self.heal_speed * setup.material.c_r * setup.dt),
                     n_heal=self.heal_steps(setup), contact=f(self.contact), soften=self.soften,
                     mu=f(self.friction), tiny=f(np.finfo(np.dtype(dtype)).tiny), **nuc)

    def heal_steps(self, setup) -> int:
        """n_heal = ceil(heal_time / dt): the steps a claim must last before the site re-bonds (HEAL_TIME);
        heal_time in l/c_r, ``setup`` gives dt (a/c) and the time unit l/c_r.  The 1e-9 keeps a heal_time
        that is a whole number of steps from rounding up by one on the division's last bit."""
        import math
        return int(math.ceil(self.heal_time * setup.t_unit / setup.dt - 1e-9))

    def site_values(self, n_sites: int) -> dict:
        """Each site's own constants {"kx", "ky", "delta_b"}: arrays over the global sites 0..n_sites-1, the
        same on every rank (the module docstring says how they are made)."""
        out = {"kx": np.full(n_sites, self.kx), "ky": np.full(n_sites, self.ky),
               "delta_b": np.full(n_sites, self.delta_b), "softening": np.full(n_sites, self.softening)}
        if self.random:
            key, cv, corr, seed = self.random
            if key == "delta_b":
                excess = self.delta_b - self.delta0
                out[key] = self.delta0 + excess * random_field(n_sites, cv * self.delta_b / excess, corr, seed)
            else:
                out[key] = out[key] * random_field(n_sites, cv, corr, seed)
        x = site_x(n_sites)
        for (lo, hi), values in self.patches:
            inside = (x >= lo) & (x < hi)
            for key, v in values:
                out[key][inside] = v
        return out

    def extremes(self, n_sites: int) -> dict:
        """{key: (min, max)} of the sites' kx, ky, delta_b, softening."""
        return {k: (float(v.min()), float(v.max())) for k, v in self.site_values(n_sites).items() if len(v)}

    def largest(self, n_sites: int) -> dict:
        """{key: the largest value over the n_sites sites} of kx, ky and delta_b: the stiffest bonds enter
        omega_max (a stiffer spring anywhere raises every eigenvalue of the stiffness or leaves it), the
        longest delta_b the halo's reach."""
        if self.uniform or n_sites == 0:
            return {"kx": self.kx, "ky": self.ky, "delta_b": self.delta_b, "softening": self.softening}
        return {k: float(v.max()) for k, v in self.site_values(n_sites).items()}

    def longest_bond(self, n_sites: int) -> float:
        """The longest a bond gets before it breaks (a), the largest over the sites of delta_b + D_c (a weakening
        bond breaks at that length at the latest): what the halo's reach must serve."""
        if self.uniform or n_sites == 0:
            return self.delta_b + self.softening
        v = self.site_values(n_sites)
        return float((v["delta_b"] + v["softening"]).max())

    def strength(self, n_sites: int, fn: float) -> dict:
        """Each site's law at rest under the total normal load ``fn`` (m c^2/a) shared evenly by the n_sites bonds
        (arrays over the global sites; module docstring): "gap" y = delta0 - (F_N/N)/k_y (a), "x_b" the shear
        stretch of its peak sqrt(delta_b^2 - y^2) (a, x0 = 0), "tau_p" = k_x x_b and "tau_r" = min(mu F_N/N,
        tau_p) (m c^2/a: forces per bond, a traction times a), "D_c" (a), and "Gamma" = tau_p x_b/2 + (tau_p -
        tau_r) D_c/2 (m c^2/a: energy per bond over its spacing a)."""
        v = self.site_values(n_sites)
        normal = fn / max(n_sites, 1)
        gap = self.delta0 - normal / v["ky"]
        xb = np.sqrt(np.maximum(v["delta_b"] ** 2 - gap ** 2, 0.0))
        tp = v["kx"] * xb
        tr = np.minimum(self.friction * normal, tp)
        return {"gap": gap, "x_b": xb, "tau_p": tp, "tau_r": tr, "D_c": v["softening"],
                "Gamma": 0.5 * tp * xb + 0.5 * (tp - tr) * v["softening"]}

    def closing_load(self, sites: int) -> float:
        """N k_y delta0 (m c^2/a): the total normal load that closes the mean gap of ``sites`` bonds at rest."""
        return sites * self.ky * self.delta0

    def unlike_reference(self) -> list[str]:
        """The rules of this law that the reference implementation (``engine.reference_engine``) does not have, as
        "key = value" text; empty when it can run the law."""
        out = []
        if self.rebond != REBOND_NEAREST:
            out.append("interface.rebond = 'facing'")
        if self.rebond_length != self.delta0:
            out.append(f"interface.rebond_within = {self.rebond_length!r}")
        if self.heal:
            out.append("interface.heal_speed or interface.heal_time")
        if not self.uniform:
            out.append("interface.patch or interface.random")
        if self.contact:
            out.append(f"interface.contact = {self.contact!r}")
        if self.soften:
            out.append("interface.softening or interface.nucleation")
        if self.friction:
            out.append(f"interface.contact_friction = {self.friction!r}")
        return out

    def shear_stiffness(self, kx: float) -> float:
        """The stiffest shear spring a site can have: the bond's ``kx`` (the largest over the sites), or with
        contact friction the contact's stick spring k_c: what enters omega_max in the bond's place."""
        return max(kx, self.contact) if self.friction > 0 else kx

    def normal_stiffness(self, ky: float) -> float:
        """The stiffest normal spring a site can have, bond (``ky``, the largest over the sites) or contact:
        what enters omega_max in the bond's place (a site is bonded or in contact, never both)."""
        return max(ky, self.contact)
