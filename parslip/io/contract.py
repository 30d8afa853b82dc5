"""The output contract: what a run file holds, in which units; one reader for analysis.

The writer (``io.output``) creates exactly these datasets and the readers
(``analysis``, ``parslip.open``, the figure code) read them through
``read_interface`` here, so writer and reader cannot drift apart.

  /interface/intact   uint8   [frames, sites]  1 where the top node's bond is intact
  /interface/partner  int32   [frames, sites]  bottom site (substrate column) it is bonded to, -1 if broken
  /interface/time     float64 [frames]         t, in l/c_r from the start of the drive
  /interface/x        float64 [sites]          reference x, in l: 0 rear edge, 1 front edge
  /interface/ux, uy   float64 [frames, sites]  displacement of the top interface nodes, in l
  /interface/sxy, syy float64 [frames, sites]  interface traction on the block, as stress in rho c_r^2:
                                               sxy = -f_x / (a rho c_r^2), syy = -f_y / (a rho c_r^2),
                                               f the interface bond's force on the top node; where broken,
                                               sxy is the contact friction's (0 without it) and syy 0;
                                               syy < 0 is compression
  /interface/friction_force  float64 [frames]  F_T, the sum over the interface bonds of their x-force on
                                               the block, and over the unbonded sites of the contact's
                                               friction (m c^2/a, F_N's unit), correctly rounded (the
                                               exact sum rounded once, so the same bits on any rank count
                                               and in any order; older files summed in site order):
                                               < 0 while the interface holds the block back
  /interface/drive_force     float64 [frames]  the sum over the driven nodes of the x-force the drive
                                               applied in the step that ended at the frame (m c^2/a),
                                               correctly rounded: the springs' force with drive.spring > 0
  /interface/mu              float64 [frames]  -F_T / F_N, the friction coefficient the interface mobilises
  /interface/step            int64   [frames]  the drive step of the frame (steps of dt; 0 = the drive's start)
  /interface/loader          float64 [frames]  v0 t in l: where the loader is (drive.spring > 0: the rigid
                                               loader the springs pull; else the driven face's prescribed x)
  /interface/kx, ky          float64 [sites]   each site's bond stiffnesses as the run used them (m c^2/a^2)
  /interface/delta_b         float64 [sites]   each site's breaking length as the run used it (a)
  /interface/events/         every bond break and re-formation of the run, in all phases (ramp, settle,
                             drive), exact to the time step; 1-D datasets of one length, sorted by step, then
                             site, then kind (a break before a re-formation of the same site in one step):
      step     int64    the drive step whose update made it (negative before the drive)
      time     float64  its time, l/c_r from the start of the drive, computed as /interface/time is
      site     int32    the global interface site (the index of /interface/x)
      kind     uint8    EVENT_BREAK = break, EVENT_FORM = re-formation (numbered in ``model.interface``)
      partner  int32    the substrate column the bond left (break) or joined (re-formation)
      energy   float64  the bond's stored energy at that step, 1/2 k_x (x_ij - x0)^2 + 1/2 k_y (y_ij -
                        delta0)^2 (m c_r^2): at the length it broke at (break; it depends on the gap, so
                        on F_N), or with the rest offset it formed with (re-formation)
      traction float64  its shear traction k_x (x_ij - x0)/a then (rho c_r^2), as the frames' sxy
      dissipated float64  the energy the bond's weakening took from its peak to its break (m c_r^2;
                        interface.softening: the staggered form /energy/softening sums); 0 for a bond that
                        broke at its peak and for a re-formation
                        (energy and traction take a weakening bond's shear stiffness as it broke)
    attributes: events_written (how many are valid), site_column0 (the substrate column facing site 0:
    at the start every site s is bonded to column site_column0 + s)
  /VTKHDF                                      transient VTKHDF UnstructuredGrid of the snapshots (the
                                               layouts: ``io.mesh``): every node (points in a, velocity
                                               in internal units, sxx, syy, sxy in rho c_r^2) and every bond
                                               as a line cell (the bulk bonds in global order, then one per
                                               interface site), cell fields interface and intact.  The
                                               bonds are stored once for all the snapshots; each snapshot
                                               has N + sites points: the N nodes in global id order, then
                                               one per site at the far end of its interface cell (its
                                               bond's substrate node, or its top node while broken or on a
                                               rigid substrate) with its top node's fields
  /snapshots/far_node int64 [snapshots * sites] the global node id at the far end of each interface cell,
                                               per snapshot (``read_snapshot_arrays`` turns the cells back
                                               into node ids).  Files written before it have no /snapshots
                                               and store every snapshot's bonds with it, as node ids (N
                                               points per snapshot); the readers here read both
  /status             string (4096 bytes)      "running", "complete", "checkpointed at step N", "interrupted
                                               at step N" or "failed: REASON" (``STATUS``, ``read_status``)
  root attributes                              resolved scene (TOML), provenance, derived constants, and the
                                               run's timings (``TIMINGS``, named timing_<name>)

A frame at drive step k records the displacements u(k) and the bond state as
it entered that step; the events of step k come after it.  Replaying the
events from the initial state (every site bonded to the column facing it)
gives every frame's ``intact`` and ``partner`` (``replay_events``).  ``/interface`` attribute ``frames_written`` says how
many frames are valid (a failed or interrupted run keeps what it wrote).
"""
from __future__ import annotations

import numpy as np

from ..model.interface import BOND_TABLE, BONDS, EVENT_KINDS
from ..model.interface import BREAK as EVENT_BREAK
from ..model.interface import FORM as EVENT_FORM

INTERFACE = "interface"

# name: (dtype, per-frame?, units)
INTERFACE_DATASETS = {
    "intact": (np.uint8, True, "1 = bond intact"),
    "partner": (np.int32, True, "bottom site index, -1 = broken"),
    "ux": (np.float64, True, "l"),
    "uy": (np.float64, True, "l"),
    "sxy": (np.float64, True, "rho c_r^2 (interface traction, -f_x/a)"),
    "syy": (np.float64, True, "rho c_r^2 (interface traction, -f_y/a; < 0 compressive)"),
    "time": (np.float64, False, "l/c_r"),
    "x": (np.float64, False, "l"),
    "friction_force": (np.float64, False, "m c^2/a (F_N's unit): sum of the bonds' and the contact friction's "
                                          "x-forces on the block"),
    "drive_force": (np.float64, False, "m c^2/a: sum of the drive's x-forces on the driven nodes"),
    "mu": (np.float64, False, "-friction_force / F_N"),
}
INTERFACE_DATASETS["step"] = (np.int64, False, "drive steps (dt), 0 = the start of the drive")
INTERFACE_DATASETS["loader"] = (np.float64, False, "l: the loader's (prescribed face's) x-displacement v0 t")
# The bond table's rows written once per site (``model.interface.BOND_TABLE``).
INTERFACE_DATASETS.update({r.name: (np.float64, False, f"{r.units} ({r.meaning}, each site's as the run used it)")
                           for r in BOND_TABLE if r.output == "site"})
# One value per site.
SITE_DATASETS = ("x",) + BONDS.site_output
FRAME_FIELDS = ("intact",) + BONDS.frame_output + ("ux", "uy", "sxy", "syy")
# One value per frame, like ``time``.
FORCE_DATASETS = ("friction_force", "drive_force", "mu")
PER_FRAME_1D = ("time", "step", "loader") + FORCE_DATASETS

# The bond events: /interface/events/<name>, name: (dtype, units).
EVENTS = "events"
EVENT_DATASETS = {
    "step": (np.int64, "drive steps (dt), negative before the drive"),
    "time": (np.float64, "l/c_r from the start of the drive"),
    "site": (np.int32, "global interface site"),
    "kind": (np.uint8, ", ".join(f"{k} = {name}" for k, name in EVENT_KINDS.items())),
    "partner": (np.int32, "substrate column left (break) or joined (re-formation)"),
    "energy": (np.float64, "m c_r^2: the bond's stored energy 1/2 k_x (x_ij - x0)^2 + 1/2 k_y (y_ij - delta0)^2 "
                           "at that step"),
    "traction": (np.float64, "rho c_r^2: the bond's shear traction k_x (x_ij - x0)/a at that step, as sxy"),
    "dissipated": (np.float64, "m c_r^2: the energy the bond's weakening took from its peak to its break "
                               "(interface.softening; 0 for a break at the peak and a re-formation)"),
}

# The energy budget: /energy/<name>, one value per interface frame (m c_r^2), in damped Verlet's discrete
# energy (``engine.kernels.budget``): the state's terms as their change since the drive started, the works
# and losses as their totals since then, so that the sources equal the sinks plus the residual:
#     work_drive + work_normal + formed + contact_switched
#         = elastic + kinetic + contact + damping + broken + softening + friction + residual.
ENERGY = "energy"
ENERGY_SOURCES = ("work_drive", "work_normal", "formed", "contact_switched")
ENERGY_SINKS = ("elastic", "kinetic", "contact", "damping", "broken", "softening", "friction")
ENERGY_DATASETS = {
    "work_drive": "the drive's work on the driven nodes, sum over steps of f . (u(n+1) - u(n-1))/2",
    "work_normal": "the normal load's work on the top face, the same sum",
    "elastic": "change of the bonds' staggered energy 1/2 u(n-1)^T K u(n) (bulk and intact interface bonds)",
    "kinetic": "change of the kinetic energy |u(n) - u(n-1)|^2 / (2 dt^2)",
    "damping": "energy the damping took: zeta |u(n+1) - u(n-1)|^2/(4 dt) per node and step (\"absolute\"), "
               "or the bonds' dashpots' work (\"bonds\")",
    "broken": "the staggered energy of each bond at the step it broke, summed",
    "formed": "the staggered energy of each bond at the step it re-formed, summed (with its new rest offset)",
    "contact": "change of the contact springs' staggered energy 1/2 k_c s(n-1) s(n) (interface.contact; s the "
               "compression delta0 - d of a free site's spring, set up from u(n-1)), with contact friction "
               "that of their stick springs too; 0 without contact",
    "contact_switched": "what the contact springs' switches added: each step sets up a free site's spring anew "
                        "from u(n) (its surface, normal and weight), so per step and site the new spring's "
                        "staggered energy at (u(n-1), u(n)) less the old one's, summed (a site that gains or "
                        "loses its contact, by a break, a re-formation or d crossing delta0, has one of the two); "
                        "with contact friction its stick spring's too, plus what friction took (so that "
                        "contact_switched - friction is what the switches changed); 0 without contact",
    "softening": "the energy the bonds' weakening took (interface.softening): per step and weakening bond, "
                 "1/2 (k(n-1) - k(n)) s(n-1) s(n) with k its secant shear stiffness and s = x_ij - x0, summed; "
                 "0 without weakening",
    "friction": "the energy the contact's friction took (interface.contact_friction): per step and site in "
                "contact, k_c p (e(n-1) + e(n))/2 with e the stretch of its stick spring along the surface and p "
                "= e(n-1) + dxi - e(n) its slip past it (dxi its slip along the surface), summed; mu times the "
                "normal force per unit slip while it slides; 0 without friction",
    "residual": "what the other terms leave: the scheme's round-off; NaN where a term is unknown",
}


def read_energy(path: str) -> dict | None:
    """The energy budget of a run file (``ENERGY_DATASETS``, cut to the frames written, m c_r^2) with ``time``
    (l/c_r); None for a file written before the budget existed."""
    import h5py

    with h5py.File(path, "r") as f:
        g = f.get(ENERGY)
        if g is None:
            return None
        n = int(f[INTERFACE].attrs.get("frames_written", g["residual"].shape[0]))
        # A term the file predates (the contact's, the weakening's, friction's) reads NaN: its residual holds it,
        # if the run had one.
        out = {name: g[name][:n] if name in g else np.full(n, np.nan) for name in ENERGY_DATASETS}
        out["time"] = f[INTERFACE]["time"][:n]
        return out


# The run's timings, root attributes named TIMING_PREFIX + name, in seconds unless said.
TIMING_PREFIX = "timing_"
TIMINGS = {
    "startup_s": "from the call to the first step: scene, omega_max, arrays, output file",
    "compile_s": "the first call of the compiled loop: compiling it, or loading it from numba's cache",
    "loop_s": "from the first step to the last (every phase, output and agreements included)",
    "drive_s": "the drive phase alone, wall clock",
    "drive_cpu_s": "the drive phase alone, CPU time of rank 0",
    "steps": "steps taken by this run (a restart counts its own)",
    "drive_steps": "drive steps taken by this run",
    "node_updates_per_s": "steps x nodes / loop_s",
}


def read_interface(path: str) -> dict:
    """The interface record of a run file: every dataset above, cut to the frames written.

    Returns a dict of numpy arrays keyed by dataset name (``t`` is an alias of
    ``time``), and ``events``: the bond events (``read_events``; None for a
    file written before events existed).  Datasets a file does not hold (older
    files have no tractions or forces) are left out.
    """
    import h5py

    with h5py.File(path, "r") as f:
        g = f[INTERFACE]
        n = int(g.attrs.get("frames_written", g["time"].shape[0]))
        out = {}
        for name, (_, per_frame, _) in INTERFACE_DATASETS.items():
            if name in g:
                out[name] = g[name][:n] if per_frame or name in PER_FRAME_1D else g[name][...]
        out["t"] = out["time"]
    out["events"] = read_events(path)
    return out


def read_events(path: str) -> dict | None:
    """The bond events of a run file (``EVENT_DATASETS``, cut to ``events_written``), with the attribute
    ``site_column0``, the time of one step ``dt`` (l/c_r: the resolution of every event time) and the top
    block's wave speeds ``c_s`` and ``c_l`` (c_r); None for a file written before events existed."""
    import h5py

    with h5py.File(path, "r") as f:
        g = f[INTERFACE].get(EVENTS)
        if g is None:
            return None
        n = int(g.attrs.get("events_written", 0))
        # A field the file predates (energy, traction) reads as NaN for each of its events.
        out = {name: g[name][:n] if name in g else np.full(n, np.nan) for name in EVENT_DATASETS}
        out["site_column0"] = int(g.attrs["site_column0"])
        a = f.attrs
        # The time of one step (the events' resolution) and the top block's wave speeds, in l/c_r and c_r.
        out["dt"] = float(a["dt"]) * float(a["c_r"]) / float(a["l"])
        out["c_s"], out["c_l"] = float(a["c_s"]) / float(a["c_r"]), float(a["c_l"]) / float(a["c_r"])
        return out


def replay_events(events: dict, n_sites: int, frame_steps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(intact, partner) [frames, sites] rebuilt from the events alone: from the initial state (site s bonded
    to column site_column0 + s), apply every event before each frame's step (a frame records the bond state as
    it entered its step).  Equal to the frames' own record: the test of a complete event record."""
    partner = np.arange(n_sites, dtype=np.int64) + events["site_column0"]
    steps, sites, kinds, cols = events["step"], events["site"], events["kind"], events["partner"]
    out = np.zeros((len(frame_steps), n_sites), np.int32)
    e = 0
    for k, s in enumerate(frame_steps):
        while e < len(steps) and steps[e] < s:
            partner[sites[e]] = -1 if kinds[e] == EVENT_BREAK else cols[e]
            e += 1
        out[k] = partner
    return (out >= 0).astype(np.uint8), out


# --- reader helpers for parslip.open and the analysis commands ----------------------------
# Every read of a run file outside the writer goes through these, so a file that
# is missing, not HDF5 or not a parslip run gives one ConfigError line (exit 2).

VTKHDF = "VTKHDF"
SNAPSHOTS = "snapshots"         # /snapshots: what the shared mesh layout keeps beside /VTKHDF
FAR_NODE = "far_node"


def check_run_file(path: str, what: str = "RUN") -> None:
    """Raise ``ConfigError`` (one line: argument, value, what is accepted) unless ``path`` is a parslip run file."""
    import os

    import h5py

    from ..errors import ConfigError

    accepted = "a parslip run file (.vtkhdf written by `parslip run`)"
    if not os.path.exists(path):
        raise ConfigError(f"{what} {path!r}: no such file; accepted: {accepted}")
    if os.path.isdir(path):
        raise ConfigError(f"{what} {path!r}: is a directory; accepted: {accepted}")
    try:
        with h5py.File(path, "r") as f:
            ok = INTERFACE in f and "time" in f[INTERFACE] and "intact" in f[INTERFACE]
    except OSError:
        raise ConfigError(f"{what} {path!r}: not an HDF5 file; accepted: {accepted}") from None
    if not ok:
        raise ConfigError(f"{what} {path!r}: HDF5 without /{INTERFACE}/time and /{INTERFACE}/intact; "
                          f"accepted: {accepted}")


# The run's status: "running", "complete", "checkpointed at step N", "interrupted at step N" or "failed: REASON",
# in the dataset /status: one fixed-length UTF-8 string of STATUS_BYTES, NUL-padded, stored contiguously and
# written whole when the file is made.  Its bytes keep their place in the file, so the writer sets its last
# value by rewriting them there after HDF5 has closed the file (``io.output``): a full disk, which can leave
# HDF5 unable to write anything more, still lets the file say that the run failed and why.  Files written
# before it hold the status as a root attribute; ``read_status`` reads either, ``read_attrs`` gives it as the
# attribute "status".
STATUS = "status"
STATUS_BYTES = 4096


def status_value(text: str) -> np.ndarray:
    """``text`` as the /status value: UTF-8, cut to STATUS_BYTES bytes (with "..." where cut), NUL-padded."""
    import h5py

    raw = text.encode("utf-8")
    if len(raw) > STATUS_BYTES:
        raw = raw[:STATUS_BYTES - 3].decode("utf-8", errors="ignore").encode("utf-8") + b"..."
    return np.array(raw, dtype=h5py.string_dtype("utf-8", STATUS_BYTES))


def status_text(value) -> str:
    """A stored status as text, its padding dropped ('' for None)."""
    if value is None:
        return ""
    if isinstance(value, (bytes, np.ndarray)):
        return bytes(value).rstrip(b"\0").decode("utf-8", errors="replace")
    return str(value)


def read_status(f) -> str:
    """The run's status from an open h5py File: /status, or the root attribute of an older file ('' if none)."""
    return status_text(f[STATUS][()] if STATUS in f else f.attrs.get(STATUS))


def put_status(f, text: str) -> None:
    """Set the status through HDF5 (collective under mpio): /status rewritten in place, or made (contiguous,
    allocated and written whole) in a file that has none, an older file's attribute removed."""
    if STATUS in f:
        f[STATUS][()] = status_value(text)
        return
    f.create_dataset(STATUS, data=status_value(text))
    if STATUS in f.attrs:
        del f.attrs[STATUS]


def read_attrs(path: str) -> dict:
    """Root attributes (resolved scene TOML, provenance, derived constants) as plain Python values."""
    import h5py

    def plain(v):
        if isinstance(v, bytes):
            return v.decode()
        if isinstance(v, np.generic):
            return v.item()
        if isinstance(v, np.ndarray):
            return v.tolist()
        return v

    with h5py.File(path, "r") as f:
        out = {k: plain(v) for k, v in f.attrs.items()}
        if STATUS in f:
            out[STATUS] = read_status(f)
        return out


def read_snapshot_times(path: str) -> np.ndarray:
    """Times of the VTKHDF snapshots, in l/c_r (empty when the run wrote none)."""
    import h5py

    with h5py.File(path, "r") as f:
        if VTKHDF not in f or "Steps" not in f[VTKHDF]:
            return np.zeros(0)
        return np.asarray(f[VTKHDF]["Steps"]["Values"][...], dtype=float)


def read_timings(path: str) -> dict:
    """The run's timings (``TIMINGS``) from its root attributes; {} for a file written without them."""
    attrs = read_attrs(path)
    return {k[len(TIMING_PREFIX):]: v for k, v in attrs.items() if k.startswith(TIMING_PREFIX)}


def read_snapshot_arrays(path: str, k: int) -> dict:
    """Snapshot ``k`` of a run file as plain arrays, without pyvista, whichever layout the file has:
    ``points`` (N, 3) positions in a, ``velocity`` (N, 3) half-step velocities (internal units) and ``sxx``,
    ``syy``, ``sxy`` (N,) stresses (rho c_r^2), all in global node id order; ``cells`` (M, 2) the line cells'
    node ids (every bulk bond, then one cell per interface site: its top node and the substrate node it is
    bonded to, the top node twice while broken), ``interface`` (M,) 1 on the interface cells, ``intact``
    (M,) 1 on the intact ones; ``time`` in l/c_r."""
    import h5py

    with h5py.File(path, "r") as f:
        g = f[VTKHDF]
        S = int(g["Steps"].attrs["NSteps"])
        if not 0 <= k < S:
            from ..errors import ConfigError
            raise ConfigError(f"snapshot {k}: out of range; accepted: 0 <= k < {S} ({path})")
        steps = g["Steps"]
        part = int(steps["PartOffsets"][k])
        m = int(g["NumberOfCells"][part])
        n = int(f.attrs["n_nodes"]) if "n_nodes" in f.attrs else int(g["NumberOfPoints"][part])
        q0 = int(steps["ConnectivityIdOffsets"][k])
        cells = g["Connectivity"][q0:q0 + 2 * m].reshape(m, 2)
        out = {"cells": cells, "time": float(steps["Values"][k])}
        for group, names, rows in (("PointData", ("velocity", "sxx", "syy", "sxy"), n),
                                   ("CellData", ("interface", "intact"), m)):
            for name in names:
                a = int(steps[f"{group}Offsets/{name}"][k])
                out[name] = g[f"{group}/{name}"][a:a + rows]
        p0 = int(steps["PointOffsets"][k])
        out["points"] = g["Points"][p0:p0 + n]
        if SNAPSHOTS in f:              # the shared mesh: interface cells end at far-end points N + s
            iface = np.flatnonzero(out["interface"] == 1)
            ns = len(iface)
            cells[iface, 1] = f[SNAPSHOTS][FAR_NODE][k * ns:(k + 1) * ns]
        return out
