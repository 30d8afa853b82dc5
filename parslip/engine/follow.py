"""Slabs and halos that follow the interface's slip.

On several ranks the interface rows' halos cover the slip reached so far plus a skin, not the slip the run
could reach: the drift box (``parallel.layout.Drift``).  At every agreement the loop reduces the drift
extremes of both interface rows over all ranks and returns REBUILD, on every rank at the same step, when
they come within half a skin (or twice their last growth) of the box's edge (``loop._near_edge``).  Then,
collectively:

1. the frames and bond events held are written out (their sites may change hands);
2. the new box: the block's columns are shifted by D so that each rank's block columns sit over its own
   substrate columns (the block's slabs follow the drift), each edge with its skin;
3. the slabs are cut again for that placement (balanced for where the block now is), and each rank sends
   the nodes, sites and driven slots it no longer owns to their new owners by global id
   (``parallel.migrate``): the nodes' u(n) and u(n-1), the drive's reference, each bond's state, and the
   energy budget's running totals per driven slot and per site;
4. the arrays, the exchange plan and the schedule are built for the new layout, filled from what arrived,
   and the halos refilled by one exchange of both levels.

Nothing in a step depends on where a slab ends, so the run continues with the same bits as on one rank.
The choice of migrating the block's nodes, rather than reaching the ranks under and over a slid block,
keeps every rank's peers to its neighbours (a window of a slab and its margins spans up to three slabs on
each side) and rebalances the slabs as the block moves over the substrate.
"""
from __future__ import annotations

import math

import numpy as np

from ..model.interface import BONDS
from ..model.lattice import BOTTOM, TOP
from ..parallel.layout import Drift, build_layout, drift_reach, follow_box
from ..parallel.migrate import NODES, SITES, Placement, redistribute
from . import loop as L


def placement(layout) -> Placement:
    return Placement(layout.bounds, layout.offsets)


def state_tables(sim) -> dict:
    """This rank's state at step ``sim.n`` as tables by global id (``parallel.migrate``): its OWNED nodes, its
    driven slots and its OWNED interface sites."""
    s, b, n = sim.state, sim.budget, sim.n
    top = s.own_block == TOP
    d0 = np.zeros(s.n_owned, s.dtype)
    d0[top] = s.drive.drive0[s.own_prow[top], s.own_j[top]]
    sl = s.owned_sites()
    site = np.arange(sl.stop - sl.start, dtype=np.int64) + (s.site0() if sim.setup.lattice.has_interface else 0)
    bonds = {name: s.iface.bonds[BONDS.names.index(name), sl].copy() for name in BONDS.names}
    return {"nodes": (NODES, s.gid, {"u": s.owned_u(n, s.dtype), "u_prev": s.owned_u(n - 1, s.dtype),
                                     "drive0": d0}),
            "slots": (NODES, s.driven_gid, {"force": s.drive.force.copy(), "work": b.work.T.copy(),
                                            "prev": b.prev.T.copy()}),
            "sites": (SITES, site, {**bonds, "budget": b.sites[:, :, sl].transpose(2, 0, 1).copy()})}


def take_tables(sim, tables: dict):
    """Set this rank's OWNED state from ``state_tables`` of the ranks that held it (the same step)."""
    s, b, n = sim.state, sim.budget, sim.n
    _, gid, nodes = tables["nodes"]
    _, slots, drive = tables["slots"]
    _, sites, bonds = tables["sites"]
    sl = s.owned_sites()
    if not (np.array_equal(gid, s.gid) and np.array_equal(slots, s.driven_gid) and len(sites) == sl.stop - sl.start):
        raise RuntimeError(f"rank {sim.rank}: the state that arrived is not the state this rank owns")
    s.set_owned_u(n, nodes["u"])
    s.set_owned_u(n - 1, nodes["u_prev"])
    top = s.own_block == TOP
    s.drive.drive0[s.own_prow[top], s.own_j[top]] = nodes["drive0"][top]
    s.drive.force[:] = drive["force"]
    b.work[:] = drive["work"].T
    b.prev[:] = drive["prev"].T
    for name in BONDS.names:
        s.iface.bonds[BONDS.names.index(name), sl] = bonds[name]
    b.sites[:, :, sl] = bonds["budget"].transpose(1, 2, 0)


def _agreed_drift(sim):
    """The drift extremes and their growth every rank agreed at the last agreement (a, drift slots' order);
    a row without sites of its own anywhere (a rigid substrate) stands still."""
    q = float(L.DRIFT_QUANTA)
    g, h = sim.diag.gflags, sim.diag.halo
    ext = [0.0 if g[L.L_DRIFT + k] == L.NO_SITES else g[L.L_DRIFT + k] / q for k in range(4)]
    return ext, [h[L.H_GROWTH + k] / q for k in range(4)]


def rebuild(sim, writer):
    """Collective: the slabs and halos for the drift agreed at the last agreement (module docstring)."""
    sim._flush(writer)
    old = sim.layout
    st = sim.setup
    ext, growth = _agreed_drift(sim)
    drift = follow_box(old.reach.drift, ext, growth, st.skin, L.DRIFT_QUANTA)
    move_to(sim, build_layout(st.lattice, sim.rank, sim.size, drift_reach(old.reach.link, drift), st.drive.mode,
                                 overlap=st.overlap))
    _count_from(sim, sim.diag.gflags[L.L_DRIFT:L.L_DRIFT + 4], drift.shift - old.reach.drift.shift)
    sim.rebuilds += 1
    if writer is not None:
        writer.follow(sim.output_sites())


def _count_from(sim, extremes, moved: int):
    """Record the agreed drift ``extremes`` (quanta, drift slots' order) relative to a shift grown by ``moved``
    columns: where the next agreement's growth counts from."""
    q = L.DRIFT_QUANTA
    h = sim.diag.halo
    for k, e in enumerate(extremes):
        if e != L.NO_SITES:
            h[L.H_PREV + k] = e - moved * q if k == 0 else (e + moved * q if k == 1 else e)


def _drift_now(sim) -> np.ndarray:
    """Collective: the interface rows' drift extremes at u(n) over every rank, in quanta (``loop._drift``'s
    slots and rounding, the MAX the agreements take), from the state of slabs of no drift."""
    lat, s = sim.setup.lattice, sim.state
    ux = s.owned_u(sim.n)[:, 0].astype(np.float64)
    rows = [(s.own_block == TOP) & (s.own_row == 0),
            (s.own_block == BOTTOM) & (s.own_row == lat.bottom.rows - 1) & (not lat.rigid)]
    ext = np.full(4, L.NO_SITES, np.int64)
    for k, sel in enumerate(rows):
        if sel.any():
            v = ux[sel]
            ext[2 * k], ext[2 * k + 1] = math.ceil(v.max() * L.DRIFT_QUANTA), math.ceil(-v.min() * L.DRIFT_QUANTA)
    if sim.comm is not None:
        from mpi4py import MPI
        sim.comm.Allreduce(MPI.IN_PLACE, ext, op=MPI.MAX)
    return ext


def move_to(sim, layout):
    """Collective: this rank's state at step ``sim.n`` moved to ``layout`` by global id, its halos filled."""
    tables = redistribute(sim.comm, sim.setup.lattice, placement(sim.layout), placement(layout), state_tables(sim))
    relayout(sim, layout)
    take_tables(sim, tables)
    sim.refill_halos()


def relayout(sim, layout):
    """Replace this rank's arrays by zeroed ones for ``layout``, keeping what is not per node or site: the
    event counters, the interface's rules as the run set them (a held prestress starts its nucleation by
    setting its step there), the budget's exact sums and what a restart carried over, the frame cursor."""
    counters = sim.state.iface.counters.copy()
    rules = sim.state.iface.rules
    acc, base = sim.budget.acc.copy(), sim.budget.base.copy()
    sim._build(layout)
    sim.state.iface = sim.state.iface._replace(rules=rules)
    sim.state.iface.counters[:] = counters
    sim.budget.acc[:] = acc
    sim.budget.base[:] = base


def checkpoint_attrs(sim) -> dict:
    """The drift box the halos serve and the loop's record of the drift (``Diag.halo``), so that a restart
    on any rank count builds the same slabs and halos and rebuilds them at the same steps."""
    if not sim.params.follow:
        return {}
    d = sim.layout.reach.drift
    return {"halo_drift": np.array([d.shift, *d.top, *d.bottom, *d.skin], np.float64),
            "halo_record": sim.diag.halo.copy(), "halo_rebuilds": sim.rebuilds}


def resume(sim, attrs: dict):
    """Collective, after a restart has filled the state in the slabs of no drift (the checkpoint's): the slabs
    and halos of the drift box the checkpoint was written with, the state migrating to them by global id
    (a checkpoint without one, or a run that does not follow the drift, keeps the first layout)."""
    if not sim.params.follow:
        return
    st, old = sim.setup, sim.layout
    if "halo_drift" in attrs:
        v = [float(x) for x in attrs["halo_drift"]]
        drift = Drift(int(v[0]), (v[1], v[2]), (v[3], v[4]), tuple(v[5:9]))
    else:
        # Written by a run whose halos did not follow (one rank, or a fixed slip reach): the box of the slip
        # the state holds, as a rebuild at this step would make it.
        ext = _drift_now(sim)
        drift = follow_box(old.reach.drift, [0.0 if e == L.NO_SITES else e / L.DRIFT_QUANTA for e in ext], [0.0] * 4,
                           st.skin, L.DRIFT_QUANTA)
    if drift != old.reach.drift:         # the box was rebuilt before the checkpoint: its slabs and halos
        move_to(sim, build_layout(st.lattice, sim.rank, sim.size, drift_reach(old.reach.link, drift), st.drive.mode,
                                 overlap=st.overlap))
    if "halo_drift" in attrs:
        sim.diag.halo[:] = np.asarray(attrs["halo_record"], np.int64)
        sim.rebuilds = int(attrs["halo_rebuilds"])
    else:
        _count_from(sim, ext, drift.shift)
