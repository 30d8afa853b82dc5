"""How much memory a run takes, per rank, predicted from the layout before anything is allocated.

The prediction adds up, for each rank, the arrays the run holds for its
whole life (from the rank's ``parallel.layout``, exactly), the arrays a
snapshot needs while it is written, and the process itself:

    peak = BASE + persistent + max(set-up transient, snapshot transient, omega_max transient)

- persistent: the state (two Verlet levels of x and y per block, with ghost
  cells and halo columns, and the drive's reference), the owned-node index
  (global id, block, row, column, array indices, reference x and y: 64 B per
  node), the bond cells the writer keeps (48 B per node), the interface
  frame buffer and the exchange buffers;
- snapshot transient: the node fields of a snapshot (u(n), u(n-1), positions,
  velocities, stresses: 104 B per node, plus 48 B of temporaries) on every
  rank; on a rank that writes through serial h5py (one rank, or rank 0 of
  the gathering writer) a fixed 30 MiB and 250 B per node of its own
  instead, measured at l = 100, 500 and 1000 on 1 and 2 ranks with 30
  snapshots (the peak grows over the first few snapshots and then stays:
  HDF5's per-dataset chunk caches and freed buffers the allocator keeps),
  plus two of the messages in which the other ranks stream their fields to
  it (``io.output.STREAM_BYTES`` each: the one it writes and the next); under
  the collective writer each rank writes its own nodes and stays near the
  152 B per node;
- set-up transient: sorting the owned nodes into global order and building
  the writer's bond cells (a few hundred columns at a time): about 100 B
  per node, measured;
- omega_max (rank 0, lattices up to 60,000 degrees of freedom): the sparse
  stiffness and its Lanczos vectors, about 1.2 kB per node;
- BASE: Python with NumPy, SciPy, numba, h5py, mpi4py and the compiled loop
  loaded, measured on this kind of machine (``parslip bench`` measures it again
  and reports the prediction against the measured peak).
"""
from __future__ import annotations

import numpy as np

from ..io.output import STREAM_BYTES

BASE = 200 << 20
INDEX_BYTES = 64
CELL_BYTES = 48
SNAPSHOT_BYTES = 152
WRITER_FIXED = 30 << 20
WRITER_BYTES = 250
SETUP_BYTES = 100
OMEGA_BYTES = 1200
FRAME_BUFFER_BYTES = 8 << 20     # interface frames held in memory between writes, per rank
FRAME_SITE_BYTES = 45            # per site and frame: intact 1 + partner 4 + ux, uy, sxy, syy, fx 8 each
FRAME_FIXED_BYTES = 8 + 440      # per frame: its step 8, the energy budget's 5 x 11 float64 (engine.loop.Frames)
FRAME_DRIVEN_BYTES = 8           # per OWNED driven node and frame: the force the drive applied (fdrive)
EVENT_BYTES = 41                 # per bond event held: step 8, site 4, kind 1, partner 4, 3 float64 (energy ...)
EVENT_BUFFER = 100_000           # bond events a rank holds before the ranks write them out, by default (4.1 MB)
# Steps between two agreements of the ranks (``engine.loop``: the checks of the state, the stop, the events).
CHECK_EVERY = 256


def frame_buffer(nsites: int, n_frames: int) -> int:
    """Frames the interface buffer of a rank with ``nsites`` OWNED sites holds (``engine.loop.Frames``):
    FRAME_BUFFER_BYTES worth, at least 16, at most the run's frames."""
    per_frame = max(nsites, 1) * FRAME_SITE_BYTES + 8
    return int(min(max(16, FRAME_BUFFER_BYTES // per_frame), n_frames))


def frame_bytes(capacity: int, sites: int, driven: int) -> int:
    """Bytes of a rank's interface frame buffer (``engine.loop.Frames``): ``capacity`` frames of its ``sites``
    OWNED sites, its ``driven`` OWNED driven nodes, the frame's step and the energy budget's terms."""
    return capacity * (sites * FRAME_SITE_BYTES + driven * FRAME_DRIVEN_BYTES + FRAME_FIXED_BYTES)


def event_room(sites: int, buffer_events: int = 0) -> tuple[int, int]:
    """(limit, capacity) of the bond-event record of a rank with ``sites`` OWNED interface sites.

    The ranks write their events out at the first agreement (every ``CHECK_EVERY`` steps) at which any rank
    holds more than ``limit`` (``output.buffer_events``, 0 = ``EVENT_BUFFER``): the same number on every rank.
    Between two agreements a rank adds at most 2 events per site and step (a break and a re-formation), so a
    record of ``limit + 2 sites CHECK_EVERY`` never overflows."""
    limit = int(buffer_events if buffer_events > 0 else EVENT_BUFFER)
    return limit, (limit + 2 * sites * CHECK_EVERY if sites > 0 else 0)


def predict_rank(setup, rank: int, ranks: int, gather: bool = True) -> int:
    """Predicted peak resident bytes of rank ``rank`` of a run of ``setup`` on ``ranks`` ranks."""
    return int(per_rank_bytes(setup, ranks, gather)[rank])


def per_rank_bytes(setup, ranks: int, gather: bool = True, counts=None, bounds=None) -> np.ndarray:
    """Predicted peak resident bytes of every rank, from the decomposition's counts in closed form
    (``parallel.counts``: no layout is built, so this stays fast at thousands of ranks); ``counts`` and
    ``bounds`` of another decomposition than the first (a slid block's) may be given."""
    from ..model.stability import LANCZOS_MAX_DOFS
    from ..parallel.counts import rank_counts
    from ..parallel.layout import owned_site_counts, slab_bounds
    lat = setup.lattice
    item = np.dtype(setup.dtype).itemsize
    snapshots = setup.n_snapshots > 0
    if bounds is None:
        bounds = slab_bounds(lat, ranks)
    c = counts if counts is not None else rank_counts(lat, bounds, setup.reach)
    state = item * (4 * c.cells[0] + 5 * c.cells[1])     # 2 levels x (x, y), and the drive's reference (top)
    owned, sites = c.nodes, c.sites
    widest = int(owned_site_counts(lat, bounds).max())  # every rank's buffer holds as many frames
    driven = np.array([lat.driven_in_columns(setup.drive.mode, setup.drive.rows, int(bounds[p]), int(bounds[p + 1]))
                       for p in range(ranks)], np.int64)
    frames = frame_bytes(frame_buffer(widest, setup.n_frames), sites, driven)
    limit = event_room(1, setup.scene["output.buffer_events"])[0]
    events = np.where(sites > 0, limit + 2 * sites * CHECK_EVERY, 0) * EVENT_BYTES
    persistent = state + owned * (INDEX_BYTES + CELL_BYTES) + frames + events
    transient = owned * SNAPSHOT_BYTES if snapshots else np.zeros(ranks, np.int64)
    if snapshots and (gather or ranks == 1):            # serial h5py: rank 0 writes, the others stream to it
        transient[0] = WRITER_FIXED + owned[0] * WRITER_BYTES + (2 * STREAM_BYTES if ranks > 1 else 0)
    omega = np.zeros(ranks, np.int64)
    if 2 * lat.n_nodes <= LANCZOS_MAX_DOFS:
        omega[0] = lat.n_nodes * OMEGA_BYTES
    return BASE + persistent + np.maximum.reduce([transient, omega, owned * SETUP_BYTES])


def predict(setup, ranks: int, gather: bool = True) -> dict:
    """Predicted peak resident bytes of each rank of a run of ``setup`` on ``ranks`` ranks."""
    per_rank = [int(v) for v in per_rank_bytes(setup, ranks, gather)]
    n = max(setup.lattice.n_nodes, 1)
    return {"per_rank": per_rank, "total": sum(per_rank),
            "bytes_per_node": (sum(per_rank) - ranks * BASE) / n}


def available_bytes() -> int | None:
    """Memory this host can still give a process (MemAvailable of /proc/meminfo), or None where unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None
