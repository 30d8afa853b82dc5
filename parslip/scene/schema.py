"""Every scene key with its default, units and accepted range.

A scene is a TOML file under ``run/``.  Every key it may hold is declared in
SCHEMA below; anything else is an error (``scene.load`` checks).  Each key
carries its default, its units, the accepted range as text shown in errors
and in `parslip keys`, and the predicate that enforces it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from ..errors import ConfigError  # noqa: F401  (re-exported: schema users raise it)
from ..io.scenefile import to_toml  # noqa: F401  (the scene as TOML text lives with the file format)


@dataclass(frozen=True)
class Key:
    default: Any
    kind: type                  # float, int, str or bool
    units: str
    accepted: str               # human text, shown in errors and `parslip keys`
    check: Callable[[Any], bool]
    help: str


def _range(lo=None, hi=None, lo_open=False, hi_open=False):
    def ok(v):
        if lo is not None and (v < lo or (lo_open and v == lo)):
            return False
        if hi is not None and (v > hi or (hi_open and v == hi)):
            return False
        return math.isfinite(v) if isinstance(v, float) else True
    return ok


def _choice(*opts):
    return lambda v: v in opts


SCHEMA: dict[str, Key] = {
    # geometry ---------------------------------------------------------------
    "lattice.top_rows": Key(10, int, "rows", ">= 2", _range(2), "rows of the sliding (top) block"),
    "lattice.top_cols": Key(100, int, "nodes", ">= 4", _range(4),
                            "nodes per row of the top block; the contact length is l = top_cols * a"),
    "lattice.bottom_rows": Key(20, int, "rows", ">= 2, or 0 for a free block with no substrate",
                               lambda v: v == 0 or v >= 2, "rows of the substrate (bottom) block"),
    "lattice.bottom_cols": Key(300, int, "nodes", ">= top_cols, same parity", _range(4),
                               "nodes per row of the substrate; the top block is centred on it"),
    "lattice.substrate": Key("elastic", str, "-", "'elastic' or 'rigid'", _choice("elastic", "rigid"),
                             "substrate model: an elastic lattice of bottom_rows rows, or its k_n -> infinity "
                             "limit, one row of fixed interface sites (no substrate nodes are computed or written)"),
    # materials --------------------------------------------------------------
    "material.nu": Key(0.2, float, "-", "-1 < nu <= 0.25 (plane strain) or <= 1/3 (plane stress)",
                       _range(-1.0, 1.0 / 3.0, lo_open=True), "Poisson ratio of the top block"),
    "material.model": Key("plane_strain", str, "-", "'plane_strain' or 'plane_stress'",
                          _choice("plane_strain", "plane_stress"), "how nu maps to c_l/c_s"),
    "material.velocity_unit": Key("c_r", str, "-", "'c_r' or 'c_s'", _choice("c_s", "c_r"),
                                  "the velocity the stiffnesses are made dimensionless with (a = m = 1): the "
                                  "top block's shear speed c_s, or its Rayleigh speed c_r (the paper's Sec. 2 "
                                  "normalises velocities by c_r); sets k_n, k_t against the fixed k_x, k_y and F_N"),
    "material.kn_spring": Key("along", str, "-", "'along' or 'across'", _choice("along", "across"),
                              "which Born spring the k_n of Eq. 2.2 (and material.bottom_kn) is: 'along' the "
                              "bond (Eq. 2.1: k_n resists its stretch, k_t its transverse motion) or 'across' "
                              "it (the text near Fig. 1: k_n perpendicular, k_t along; the two swap)"),
    "material.bottom_kn": Key(100.0, float, "m c^2/a^2", "> 0", _range(0.0, lo_open=True),
                              "normal bond stiffness of the substrate"),
    "material.bottom_kt": Key(0.0, float, "m c^2/a^2", ">= 0", _range(0.0),
                              "transverse bond stiffness of the substrate"),
    # interface --------------------------------------------------------------
    "interface.kx": Key(0.1, float, "m c^2/a^2", ">= 0", _range(0.0), "shear stiffness of an interface bond"),
    "interface.ky": Key(0.3, float, "m c^2/a^2", "> 0", _range(0.0, lo_open=True),
                        "normal stiffness of an interface bond"),
    "interface.delta0": Key(0.5, float, "a", "> 0", _range(0.0, lo_open=True),
                            "unloaded gap; a free top node re-bonds within this distance"),
    "interface.delta_b": Key(0.7, float, "a", "> delta0", _range(0.0, lo_open=True),
                             "bond length at which an interface bond breaks"),
    "interface.reform_x0": Key("zero", str, "-", "'zero' or 'current'", _choice("current", "zero"),
                               "rest offset x_ij^0 of a re-formed bond (Eq. 2.3): 0, that of two facing nodes, "
                               "as for the bonds of the initial state; or its offset when it forms (it starts "
                               "unstressed in x)"),
    "interface.rebond": Key("nearest", str, "-", "'nearest' or 'facing'", _choice("nearest", "facing"),
                            "which substrate node a free top node re-bonds to: the nearest free one within "
                            "interface.rebond_within, or only the one facing it (the nearest column)"),
    "interface.rebond_within": Key(0.0, float, "a", ">= 0 (0 = auto: delta0, the paper's delta_new <= delta0)",
                                   _range(0.0), "largest bond length at which a free top node re-bonds"),
    "interface.patch": Key([], list, "-", "an array of tables [[interface.patch]], each with x = [from, to] in l "
                           "(0 <= from < to <= 1) and any of kx, ky (>= 0, > 0), delta_b (> delta0), softening "
                           "(>= 0)",
                           lambda v: isinstance(v, list),
                           "stretches of the contact with their own bond properties: a site at x (l, from the "
                           "rear edge) with from <= x < to takes the patch's values; later patches override "
                           "earlier ones and the random field"),
    "interface.random.key": Key("delta_b", str, "-", "'kx', 'ky', 'delta_b' or 'softening'",
                                _choice("kx", "ky", "delta_b", "softening"),
                                "the bond property the seeded random field varies"),
    "interface.random.cv": Key(0.0, float, "-", ">= 0 (0 = no random field)", _range(0.0),
                               "coefficient of variation of the random field (lognormal: k_x, k_y and D_c stay "
                               "positive, delta_b above delta0)"),
    "interface.random.correlation": Key(0.0, float, "a", ">= 0 (0 = uncorrelated sites)", _range(0.0),
                                        "correlation length of the random field along the contact"),
    "interface.random.seed": Key(0, int, "-", ">= 0", _range(0),
                                 "seed of the random field (numpy PCG64): the same field on any rank count"),
    "interface.heal_speed": Key(0.0, float, "c_r", ">= 0 (0 = no condition, the paper)", _range(0.0),
                                "a free site re-bonds only while its x-velocity relative to the substrate site it "
                                "claims is below this (rate-dependent re-adhesion)"),
    "interface.heal_time": Key(0.0, float, "l/c_r", ">= 0 (0 = at once, the paper)", _range(0.0),
                               "a free site re-bonds only after claiming the same substrate site (the nearest "
                               "free one within reach) for this long; the clock restarts when the claim changes"),
    "interface.contact": Key(0.0, float, "m c^2/a^2", ">= 0 (0 = none, the paper)", _range(0.0),
                             "stiffness of the frictionless contact that keeps an unbonded top site at least "
                             "delta0 above the substrate's surface (a one-sided spring; enters omega_max)"),
    "interface.softening": Key(0.0, float, "a", ">= 0 (0 = none: a bond breaks at its peak, the paper)", _range(0.0),
                               "slip-weakening distance D_c: from its peak (where the length test first holds) a "
                               "bond's shear traction falls linearly over a further slip D_c to the residual (mu "
                               "times its normal force with interface.contact_friction, else 0), unloading along "
                               "the secant to the origin, then it breaks; patches and the random field may set it "
                               "per site"),
    "interface.contact_friction": Key(0.0, float, "-", ">= 0 (0 = none: a frictionless contact); > 0 needs "
                                      "interface.contact > 0", _range(0.0),
                                      "Coulomb friction coefficient mu of the contact: a site in contact carries a "
                                      "shear traction of at most mu times its contact's normal force, against its "
                                      "slip; also sets the residual of a weakening bond (mu times its normal force)"),
    "interface.nucleation.kind": Key("none", str, "-", "'none', 'time' or 'forced'", _choice("none", "time", "forced"),
                                     "a rupture started in the contact: 'time', the zone's bonds weaken to their "
                                     "residual over nucleation.duration; 'forced', a front from the zone's centre "
                                     "grows at nucleation.speed to its ends, each site it reaches weakening so"),
    "interface.nucleation.x": Key([], list, "l", "[from, to] with 0 <= from < to <= 1, holding a site (with a kind)",
                                  lambda v: isinstance(v, list), "the zone of the contact the nucleation weakens "
                                  "(a site at x, l from the rear edge, with from <= x < to)"),
    "interface.nucleation.duration": Key(0.0, float, "l/c_r", ">= 0 (0 = at once)", _range(0.0),
                                         "how long a site of the zone takes to weaken to its residual once its "
                                         "forcing starts"),
    "interface.nucleation.speed": Key(0.0, float, "c_r", "> 0 with kind = 'forced' (0 = unused)", _range(0.0),
                                      "the speed at which a forced nucleation's front grows from the zone's centre"),
    "interface.nucleation.start": Key(0.0, float, "l/c_r", ">= 0", _range(0.0),
                                      "when the nucleation starts: after the held prestress has settled "
                                      "(drive.prestress), else after the drive's start"),
    "interface.slip_reach": Key(0.0, float, "a", ">= 0 (0 = auto: the halos follow the slip reached)", _range(0.0),
                                "with several ranks: 0, the slabs and halos follow the interface's slip as it "
                                "grows (rebuilt when it nears the halo's edge); > 0, fixed halos that serve this "
                                "largest slip of the block's interface relative to the substrate's"),
    "interface.halo_skin": Key(0.0, float, "a", ">= 0 (0 = auto: 4 links ahead, 1 behind the drive)", _range(0.0),
                               "with several ranks and an automatic slip reach: how far beyond the slip reached "
                               "the interface halos reach in the direction of slip (a quarter of it against it, "
                               "at least one link); they are rebuilt once the slip comes within half of it"),
    # load and drive -------------------------------------------------------------
    "load.FN": Key(1.0, float, "m c^2/a", ">= 0", _range(0.0),
                   "total normal load, spread evenly over the top row SR"),
    "load.ramp": Key(0.5, float, "l/c_r", ">= 0", _range(0.0), "time to ramp F_N up linearly"),
    "load.settle": Key(4.0, float, "l/c_r", ">= 0", _range(0.0), "damped settling time at full F_N"),
    "drive.mode": Key("push", str, "-", "'push' (T-), 'pull' (T+), 'shear' (T0) or 'none'",
                      _choice("push", "pull", "shear", "none"), "which face is driven"),
    "drive.hold": Key("x", str, "-", "'x' or 'xy'", _choice("x", "xy"),
                      "what the drive prescribes on the driven face: x only (y free), or x and y (y held at "
                      "its value when the drive starts)"),
    "drive.spring": Key(0.0, float, "m c^2/a^2", ">= 0 (0 = prescribed motion, the paper)", _range(0.0),
                        "stiffness of the spring that ties each driven node to a rigid loader moving at v0 (a "
                        "compliant load cell: the contact can stick and slip); enters omega_max"),
    "drive.rows": Key([], list, "rows", "[] (every row) or [first, last] with 0 <= first <= last < top_rows; "
                      "push and pull only", lambda v: isinstance(v, list),
                      "the rows of the driven face the push or pull acts on, counted from the interface row 0 "
                      "(a loading point at a chosen height)"),
    "drive.prestress.tau0": Key(0.0, float, "rho c_r^2", ">= 0 (0 = none: the drive runs to the end), below the "
                                "interface's mean peak strength", _range(0.0),
                                "hold a prestress: stop the drive once the interface's mean shear traction over "
                                "drive.prestress.x (summed exactly, the same on any rank count) reaches this, and "
                                "hold the driven face there while the lattice settles"),
    "drive.prestress.settle": Key(2.0, float, "l/c_r", ">= 0", _range(0.0),
                                  "how long the held prestress settles before a nucleation starts"),
    "drive.prestress.x": Key([0.0, 1.0], list, "l", "[from, to] with 0 <= from < to <= 1, holding a site",
                             lambda v: isinstance(v, list), "the stretch of the contact whose sites' mean shear "
                             "traction the prestress reads (e.g. inside strong edge patches)"),
    "drive.v0": Key(1e-3, float, "c_r", "> 0", _range(0.0, lo_open=True), "drive velocity"),
    "drive.duration": Key(100.0, float, "l/c_r", "> 0", _range(0.0, lo_open=True),
                          "simulated drive time after settling"),
    # time integration ---------------------------------------------------------
    "time.safety": Key(0.9, float, "-", "0 < safety <= 1", _range(0.0, 1.0, lo_open=True),
                       "dt = safety * 2/omega_max"),
    "time.dt": Key(0.0, float, "a/c", "0 (auto) or 0 < dt < 2/omega_max", _range(0.0),
                   "explicit time step; overrides time.safety"),
    "time.zeta": Key(0.1, float, "c/a", ">= 0", _range(0.0), "velocity damping"),
    "time.damping": Key("absolute", str, "-", "'absolute' or 'bonds'", _choice("absolute", "bonds"),
                        "what zeta damps: 'absolute' every node's velocity (the paper's body drag), 'bonds' each "
                        "bulk bond's rate of deformation (a rigid translation is not braked; shortens dt)"),
    "time.precision": Key("float64", str, "-", "'float64' or 'float32'", _choice("float64", "float32"),
                          "float type of the state; float32 stores displacements from the reference lattice"),
    # output -------------------------------------------------------------------
    "output.interface_dt": Key(0.0, float, "l/c_r", ">= 0 (0 = auto: a/c_r, one frame per spacing a front at c_r crosses)",
                               _range(0.0), "interval between interface frames"),
    "output.snapshots": Key(20, int, "-", ">= 0", _range(0), "whole-lattice snapshots over the drive, plus one at its start"),
    "output.fields": Key("all", str, "-", "'all' or 'interface'", _choice("all", "interface"),
                         "what a run writes: the interface record and whole-lattice snapshots, or the "
                         "interface record only (no snapshot is computed, held or written)"),
    "output.energy": Key("balance", str, "-", "'balance' or 'checked'", _choice("balance", "checked"),
                         "the energy budget's damping (/energy): 'balance' what the other terms leave (free; the "
                         "residual reads NaN), 'checked' the body drag summed node by node every step (about a "
                         "fifth more per step; the residual then measures the budget's closure)"),
    "output.progress_s": Key(10.0, float, "s", "> 0", _range(0.0, lo_open=True),
                             "wall-clock interval between progress lines (at most 30 s without a terminal)"),
    "output.buffer_frames": Key(0, int, "frames", ">= 0 (0 = auto: 8 MiB of frames on the widest slab)",
                                _range(0), "interface frames held in memory between writes, the same on every "
                                "rank; changes no result"),
    "output.buffer_events": Key(0, int, "events", ">= 0 (0 = auto: 100,000)", _range(0),
                                "bond events a rank may hold before every rank writes its events out (checked "
                                "every 256 steps; the record has room for what can happen in between); changes "
                                "no result"),
    # checkpoints -------------------------------------------------------------------
    "checkpoint.every": Key(0.0, float, "l/c_r", ">= 0 (0 = none on a simulated-time cadence)", _range(0.0),
                            "simulated time between checkpoints (OUT.ckpt.h5, replaced atomically)"),
    "checkpoint.wall": Key(0.0, float, "s", ">= 0 (0 = none on a wall-clock cadence)", _range(0.0),
                           "wall-clock time between checkpoints"),
    # the run's supervision ---------------------------------------------------------
    "run.overlap": Key(False, bool, "-", "true or false",
                       lambda v: isinstance(v, bool),
                       "on several ranks: update the columns a peer keeps first, send them, and update the rest while "
                       "the messages travel (each row cut in two); false: update each row whole, then exchange.  "
                       "Overlap pays only where a message takes longer than cutting every row costs (about 0.1 us "
                       "per row of the slab here: docs/hpc/scaling.md); the results are the same bits either way"),
    "run.exchange": Key("auto", str, "-", "'auto' or 'messages'", _choice("auto", "messages"),
                        "on several ranks: how halo copies travel.  'auto': between ranks on one node through "
                        "shared memory (an MPI-3 window each rank writes its peers' copies into, with a flag "
                        "per message: no MPI call a step), between nodes by MPI messages; 'messages': MPI "
                        "messages everywhere.  The results are the same bits either way"),
    "run.watchdog": Key(180.0, float, "s", ">= 0 (0 = off)", _range(0.0),
                        "on several ranks: end the job (exit 3, output marked failed) when the ranks have not "
                        "agreed for this long; --watchdog overrides it"),
}

SECTIONS = sorted({k.split(".")[0] for k in SCHEMA})


def describe_keys() -> str:
    rows = [f"{'key':26s} {'default':>14s}  {'units':10s} accepted"]
    for name, k in SCHEMA.items():
        rows.append(f"{name:26s} {k.default!r:>14s}  {k.units:10s} {k.accepted}\n{'':28s}{k.help}")
    return "\n".join(rows)
