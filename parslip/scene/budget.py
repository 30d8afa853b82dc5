"""What a scene costs before it runs, and what the engine leaves out of it.

For `parslip info`; every number is computed from the ``Setup``:

- cost: node updates = lattice nodes x steps (the unit `parslip bench`
  measures its throughput in), and the wall time they take at THROUGHPUT
  node updates per second per rank;
- output: the bytes of data the run file's datasets hold (``io.contract``,
  ``io.output``), without HDF5's own few kilobytes of metadata;
- left out: what the engine does not build or compute for this scene, and
  what that saves in bytes (``scene.memory.predict`` of the scene with and
  without it) and in node updates or multiplications per step.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .memory import predict
from ..io.contract import (ENERGY_DATASETS, EVENT_DATASETS, FRAME_FIELDS, INTERFACE_DATASETS, PER_FRAME_1D,
                           SITE_DATASETS, STATUS_BYTES)
from ..model.lattice import BOTTOM, Lattice
from .schema import SCHEMA

# Node updates per second per rank of the compiled loop on this kind of machine (2-core x86-64, one
# rank per core), by state precision: measured by `parslip bench` (its "per rank" column), which counts
# lattice nodes x steps per wall second of the time loop.  float32 moves half the bytes.
THROUGHPUT = {"float64": 600e6, "float32": 1200e6}

# The snapshots (``io.mesh``, the shared layout).  Per snapshot: each point (the nodes, and one far end per
# interface site) has Points and velocity (3 float64 each) and sxx, syy, sxy (one each); each line cell its
# intact flag (uint8); each site its far end's node id (int64); and the step's time, 5 Steps offsets and 6
# field offsets.  Once, the bonds: per line cell its type (uint8), offset (int64), 2 connectivity ids
# (int64) and interface flag (uint8), one more offset and the 3 NumberOf* counts.
SNAPSHOT_POINT_BYTES = 3 * 8 + 3 * 8 + 3 * 8
SNAPSHOT_CELL_BYTES = 1
SNAPSHOT_SITE_BYTES = 8
SNAPSHOT_FIXED_BYTES = 8 + 5 * 8 + 6 * 8
MESH_CELL_BYTES = 1 + 8 + 2 * 8 + 1
MESH_FIXED_BYTES = 8 + 3 * 8
# Node stresses sxx, syy, sxy in float64, as a snapshot computes them.
STRESS_BYTES = 3 * 8


def node_updates(st) -> int:
    """Lattice nodes x steps: the work of the whole run in `parslip bench`'s unit."""
    return st.lattice.n_nodes * st.n_steps


def wall_seconds(st, ranks: int = 1) -> float:
    """node_updates / (THROUGHPUT[precision] x ranks), s: the time loop at perfect scaling."""
    return node_updates(st) / (THROUGHPUT[st.precision] * ranks)


def bulk_cells(lat: Lattice) -> int:
    """Bulk bonds of the numbered blocks: R (C - 1) along the rows and 2C - 1 between each pair of rows."""
    return sum(b.rows * (b.cols - 1) + (b.rows - 1) * (2 * b.cols - 1)
               for i, b in enumerate(lat.blocks) if lat.numbered[i] and b.rows)


# Bytes of one bond event in the run file: the sum over the contract's event datasets (step 8, time 8, site 4,
# kind 1, partner 4, energy 8, traction 8), so a field added there counts here too.
EVENT_FILE_BYTES = sum(np.dtype(dtype).itemsize for dtype, _ in EVENT_DATASETS.values())


def output_bytes(st) -> dict:
    """Bytes of data in the run file: {'interface': ..., 'snapshots': ..., 'total': ...}.

    interface: frames x sites x (intact 1 + partner 4 + ux, uy, sxy, syy 8 each) + 8 per frame for each
    of time, step, friction_force, drive_force and mu and each term of the energy budget + 8 per site for
    each of x, kx, ky, delta_b; snapshots: each holds every node and one far end per interface site (72 B
    each), a flag per bond (1 B: bulk bonds and one per interface site), each site's far-end node id (8 B)
    and a few offsets, and the bonds are stored once for all of them (26 B each).
    The run's status (``STATUS_BYTES``, written whole when the file is made) is in the total; the bond
    events add ``EVENT_FILE_BYTES`` per event on top: how many the run makes depends on its physics, so
    they are not in the total.
    """
    lat = st.lattice
    frames, sites = st.n_frames, lat.n_top_sites
    per_site = sum(INTERFACE_DATASETS[name][0]().itemsize for name in FRAME_FIELDS)
    iface = (frames * sites * per_site + frames * 8 * (len(PER_FRAME_1D) + len(ENERGY_DATASETS))
             + sites * 8 * len(SITE_DATASETS))
    cells = bulk_cells(lat) + sites
    per_snapshot = ((lat.n_nodes + sites) * SNAPSHOT_POINT_BYTES + cells * SNAPSHOT_CELL_BYTES
                    + sites * SNAPSHOT_SITE_BYTES + SNAPSHOT_FIXED_BYTES)
    snaps = st.n_snapshots * per_snapshot + (cells * MESH_CELL_BYTES + MESH_FIXED_BYTES if st.n_snapshots else 0)
    return {"interface": iface, "snapshots": snaps, "total": iface + snaps + STATUS_BYTES}


def integrated_nodes(lat: Lattice) -> int:
    """Nodes the loop advances: all but the fixed row AB of an elastic substrate."""
    fixed = lat.bottom.cols if lat.numbered[BOTTOM] else 0
    return lat.n_nodes - fixed


def _memory_total(st, ranks: int) -> int:
    return predict(st, ranks)["total"]


def _mib(b: float) -> str:
    return f"{b / 2 ** 20:.3g} MiB"


def left_out(st, ranks: int = 1) -> list[tuple[str, str]]:
    """[(item, what it saves)] for what the engine leaves out of this scene; empty when nothing is.

    Items: 'snapshots' (none asked for: no snapshot arrays, no VTKHDF group), 'stresses' (node stresses
    only at the snapshot steps), 'damping' (zeta = 0: the damping product skipped), 'fixed row' (the
    elastic substrate's row AB is held, not integrated), 'substrate' (rigid: no substrate nodes at all).
    """
    s, lat = st.scene, st.lattice
    steps = st.n_steps
    out = []
    if st.n_snapshots == 0 and lat.n_nodes:
        # What the scene would hold and write with snapshots: its own count if output.fields = "interface"
        # switched them off, else the default.
        asked = s["output.snapshots"] if s["output.fields"] == "interface" and s["output.snapshots"] else \
            SCHEMA["output.snapshots"].default
        k = asked + 1
        alt = dataclasses.replace(st, snapshot_steps=tuple(range(k)))
        mem = _memory_total(alt, ranks) - _memory_total(st, ranks)
        disk = output_bytes(alt)["snapshots"]
        why = "output.fields = 'interface'" if s["output.fields"] == "interface" else "output.snapshots = 0"
        out.append(("snapshots", f"none ({why}): no snapshot arrays, no node fields or stresses computed, no "
                                 f"VTKHDF group; saves {_mib(mem)} of peak memory and {_mib(disk)} of output "
                                 f"against {k} snapshots"))
    elif lat.n_nodes:
        held = lat.n_nodes * STRESS_BYTES
        out.append(("stresses", f"node stresses only at the {st.n_snapshots} snapshot steps, never per step and "
                                f"not held between snapshots: {lat.n_nodes * (steps - st.n_snapshots):.3g} "
                                f"node-stress evaluations not made, {_mib(held)} not held"))
    if s["time.zeta"] == 0:
        n = integrated_nodes(lat)
        out.append(("damping", f"zeta = 0: the damping product B (u(t) - u(t-dt)) is skipped, 2 multiplications "
                               f"per node update: {2 * n} per step, {2 * n * steps:.3g} over the run"))
    if lat.numbered[BOTTOM]:
        n = lat.bottom.cols
        out.append(("fixed row", f"the substrate's row AB ({n} nodes) is held at zero and never integrated: "
                                 f"{n} node updates per step, {n * steps:.3g} over the run"))
    if lat.rigid and s["lattice.bottom_rows"] >= 2:
        # Against the elastic substrate of the same scene keys (same time step: what the nodes alone cost).
        el = Lattice(s["lattice.top_rows"], s["lattice.top_cols"], s["lattice.bottom_rows"],
                     s["lattice.bottom_cols"], s["interface.delta0"], "elastic")
        alt = dataclasses.replace(st, lattice=el)
        n = el.n_nodes - lat.n_nodes
        mem = _memory_total(alt, ranks) - _memory_total(st, ranks)
        disk = output_bytes(alt)["total"] - output_bytes(st)["total"]
        out.append(("substrate", f"rigid: its {s['lattice.bottom_rows']} x {s['lattice.bottom_cols']} = {n} nodes "
                                 f"are neither held nor updated (its interface sites are fixed points): "
                                 f"{n} node updates per step ({n * steps:.3g} over the run), {_mib(mem)} of "
                                 f"memory and {_mib(disk)} of output saved against the elastic substrate"))
    return out
