"""Slabs in x, halos, and the exchanges between neighbouring ranks.

Responsible for who owns which node and which copies each rank keeps.  The
lattice is cut into slabs of whole global columns, balanced by node count.
A rank's local arrays hold its OWNED nodes first (in global order), then
its HALO: copies of the nodes of the LEFT neighbour, then of the RIGHT one.

Halo reach, in columns beyond the slab edge:

    bulk rows                      1        (every bond spans at most one column)
    top interface row              4        (claims of neighbouring free top nodes, with margin)
    bottom interface row           W = ceil(slip_reach) + 6

W follows the interface: a top node that has slid s columns bonds to a
bottom node s columns away, which may belong to the next slab.  Halos come
only from the two immediate neighbours, so no slab may be narrower than W;
that sets how many ranks a scene can use.  At the ends of the domain the
neighbour is ``MPI.PROC_NULL`` and the exchange is a no-op on that side.

The time loop talks to an exchanger, never to MPI directly:
``NullExchanger`` for one rank, ``SlabExchanger`` for several.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from ..model.lattice import Lattice

LEFT, RIGHT = 0, 1
SIDES = (LEFT, RIGHT)
OWNED, HALO = "owned", "halo"

BULK_REACH = 1
TOP_SITE_REACH = 4


def bottom_site_reach(slip_reach: float) -> int:
    return int(math.ceil(slip_reach)) + 6


def partition(col_work: np.ndarray, nranks: int, min_width: int) -> np.ndarray:
    """Column boundaries [b0=0, b1, ..., bP=ncols] balancing the work per slab.

    Boundary k is the column where the cumulative work first reaches k/P of
    the total, then nudged so every slab is at least ``min_width`` wide.
    Returns None when the lattice cannot be split that many ways.
    """
    ncols = len(col_work)
    if nranks * min_width > ncols:
        return None
    cum = np.concatenate([[0], np.cumsum(col_work)])
    bounds = [0]
    for k in range(1, nranks):
        target = cum[-1] * k / nranks
        c = int(np.searchsorted(cum, target, side="left"))
        c = max(c, bounds[-1] + min_width)               # this slab wide enough
        c = min(c, ncols - (nranks - k) * min_width)     # room for the rest
        bounds.append(c)
    bounds.append(ncols)
    return np.array(bounds, np.int64)


def max_ranks(lattice: Lattice, reach: int) -> int:
    return max(1, lattice.ncols // max(reach, 1))


@dataclass
class Channel:
    """Index lists for one kind of exchange with each side.

    ``send[side]``: local indices of owned items the neighbour on ``side``
    keeps as halo.  ``recv[side]``: local indices of my halo copies of that
    neighbour's items.  Both sides order them by global id.
    """
    send: list = field(default_factory=lambda: [np.zeros(0, np.int64)] * 2)
    recv: list = field(default_factory=lambda: [np.zeros(0, np.int64)] * 2)


@dataclass
class LocalLayout:
    """One rank's view: its slab, its local nodes and its exchange lists."""
    rank: int
    size: int
    bounds: np.ndarray          # global column boundaries of all slabs
    nodes: dict                 # per local node: gid, block, row, col, x, y
    n_owned: int
    node_channel: Channel       # forward: positions of halo nodes
    top_gsite: np.ndarray       # global top-site index of each local top site
    top_node: np.ndarray        # local node index of each local top site
    top_owned: np.ndarray       # bool
    top_channel: Channel        # forward: bond state of halo top sites
    bot_gsite0: int             # global index of the first local bottom site
    bot_node: np.ndarray        # local node index of local bottom sites (contiguous global range)
    react_channel: Channel      # reverse: reactions on halo bottom sites, by node index
    reach: int

    @property
    def col_range(self):
        return int(self.bounds[self.rank]), int(self.bounds[self.rank + 1])

    def region(self, name):
        """Slice of local node indices for OWNED or HALO."""
        return slice(0, self.n_owned) if name == OWNED else slice(self.n_owned, len(self.nodes["gid"]))


def _halo_reach(lattice: Lattice, nodes: dict, w_bottom: int) -> np.ndarray:
    reach = np.full(len(nodes["gid"]), BULK_REACH, np.int64)
    reach[lattice.is_top_site(nodes)] = TOP_SITE_REACH
    reach[lattice.is_bottom_site(nodes)] = w_bottom
    return reach


def _select(nodes: dict, mask: np.ndarray) -> dict:
    return {k: v[mask] for k, v in nodes.items()}


def build_layout(lattice: Lattice, rank: int, size: int, slip_reach: float) -> LocalLayout:
    w_bottom = bottom_site_reach(slip_reach) if (lattice.has_interface and size > 1) else BULK_REACH
    reach = max(w_bottom, TOP_SITE_REACH) if size > 1 else 1
    bounds = partition(lattice.col_count, size, reach)
    if bounds is None:
        raise ConfigError(
            f"ranks = {size}: the lattice has {lattice.ncols} columns and every slab needs at least "
            f"{reach} (the halo reach for interface slip); accepted: 1 to {max_ranks(lattice, reach)} ranks")
    c0, c1 = int(bounds[rank]), int(bounds[rank + 1])
    own = lattice.nodes_in_columns(c0, c1)
    parts = [own]
    halo_side = []
    for side, (h0, h1) in ((LEFT, (c0 - reach, c0)), (RIGHT, (c1, c1 + reach))):
        cand = lattice.nodes_in_columns(h0, h1)
        r = _halo_reach(lattice, cand, w_bottom)
        dist = (c0 - cand["col"]) if side == LEFT else (cand["col"] - c1 + 1)
        part = _select(cand, dist <= r)
        parts.append(part)
        halo_side.append(part)
    nodes = {k: np.concatenate([p[k] for p in parts]) for k in own}
    n_owned = len(own["gid"])
    n_left = len(halo_side[LEFT]["gid"])

    # Node channel: what my neighbours keep of my owned nodes, by the same rule.
    nch = Channel()
    nch.recv = [np.arange(n_owned, n_owned + n_left), np.arange(n_owned + n_left, len(nodes["gid"]))]
    r_own = _halo_reach(lattice, own, w_bottom)
    send_left = (own["col"] - c0) < r_own          # in the LEFT neighbour's right halo
    send_right = (c1 - 1 - own["col"]) < r_own
    nch.send = [np.flatnonzero(send_left) if rank > 0 else np.zeros(0, np.int64),
                np.flatnonzero(send_right) if rank < size - 1 else np.zeros(0, np.int64)]
    if rank == 0:
        nch.recv[LEFT] = np.zeros(0, np.int64)
    if rank == size - 1:
        nch.recv[RIGHT] = np.zeros(0, np.int64)

    # Interface sites.
    is_top = lattice.is_top_site(nodes)
    top_idx = np.flatnonzero(is_top)
    order = np.argsort(nodes["gid"][top_idx], kind="stable")
    top_node = top_idx[order]
    top_gsite = lattice.top_site_of_col(nodes["col"][top_node]).astype(np.int64)
    top_owned = top_node < n_owned
    pos_of_site = {int(s): i for i, s in enumerate(top_gsite)}
    tch = Channel()
    for side in SIDES:
        tch.send[side] = np.array([pos_of_site[lattice.top_site_of_col(nodes["col"][i])]
                                   for i in nch.send[side] if is_top[i]], np.int64)
        tch.recv[side] = np.array([pos_of_site[lattice.top_site_of_col(nodes["col"][i])]
                                   for i in nch.recv[side] if is_top[i]], np.int64)

    is_bot = lattice.is_bottom_site(nodes)
    bot_idx = np.flatnonzero(is_bot)
    bot_idx = bot_idx[np.argsort(nodes["col"][bot_idx], kind="stable")]
    bot_cols = nodes["col"][bot_idx]
    if len(bot_cols) and not np.array_equal(bot_cols, np.arange(bot_cols[0], bot_cols[0] + len(bot_cols))):
        raise AssertionError("bottom interface sites of a rank must be contiguous")
    bot_gsite0 = int(bot_cols[0]) if len(bot_cols) else 0

    # Reactions travel back from my halo copies of bottom sites to their owners.
    rch = Channel()
    for side in SIDES:
        rch.send[side] = np.array([i for i in nch.send[side] if is_bot[i]], np.int64)
        rch.recv[side] = np.array([i for i in nch.recv[side] if is_bot[i]], np.int64)
    return LocalLayout(rank=rank, size=size, bounds=bounds, nodes=nodes, n_owned=n_owned,
                       node_channel=nch, top_gsite=top_gsite, top_node=top_node.astype(np.int64),
                       top_owned=top_owned, top_channel=tch, bot_gsite0=bot_gsite0,
                       bot_node=bot_idx.astype(np.int64), react_channel=rch, reach=reach)


class NullExchanger:
    """The exchanger of a single rank: there is no halo, so nothing moves."""

    rank, size = 0, 1

    def forward(self, channel, *arrays):
        pass

    def reverse_add(self, channel, array):
        pass


class SlabExchanger:
    """Halo exchange with the LEFT and RIGHT neighbours over MPI.

    ``forward`` copies owned values into the neighbours' halo copies;
    ``reverse_add`` sends halo values back and adds them onto the owners.
    Several arrays travel in one message per side.
    """

    def __init__(self, comm):
        from mpi4py import MPI
        self.comm = comm
        self.rank, self.size = comm.Get_rank(), comm.Get_size()
        self.nbr = [self.rank - 1 if self.rank > 0 else MPI.PROC_NULL,
                    self.rank + 1 if self.rank < self.size - 1 else MPI.PROC_NULL]
        self._bufs = {}

    def _buf(self, key, n):
        b = self._bufs.get(key)
        if b is None or len(b) != n:
            b = self._bufs[key] = np.empty(n)
        return b

    def forward(self, channel, *arrays):
        widths = [a[0].size if a.ndim > 1 else 1 for a in arrays]
        w = sum(widths)
        # Send to LEFT while receiving from RIGHT, then the mirror image.
        for send_side, recv_side in ((LEFT, RIGHT), (RIGHT, LEFT)):
            sidx, ridx = channel.send[send_side], channel.recv[recv_side]
            sbuf = self._buf((id(channel), "s", send_side), len(sidx) * w).reshape(len(sidx), w)
            rbuf = self._buf((id(channel), "r", recv_side), len(ridx) * w).reshape(len(ridx), w)
            col = 0
            for a, wd in zip(arrays, widths):
                sbuf[:, col:col + wd] = a[sidx].reshape(len(sidx), wd)
                col += wd
            self.comm.Sendrecv(sbuf, dest=self.nbr[send_side], sendtag=send_side,
                               recvbuf=rbuf, source=self.nbr[recv_side], recvtag=send_side)
            col = 0
            for a, wd in zip(arrays, widths):
                if len(ridx):
                    a[ridx] = rbuf[:, col:col + wd].reshape(a[ridx].shape)
                col += wd

    def reverse_add(self, channel, array):
        w = array[0].size if array.ndim > 1 else 1
        for send_side, recv_side in ((LEFT, RIGHT), (RIGHT, LEFT)):
            sidx, ridx = channel.recv[send_side], channel.send[recv_side]
            sbuf = self._buf((id(channel), "rs", send_side), len(sidx) * w).reshape(len(sidx), w)
            rbuf = self._buf((id(channel), "rr", recv_side), len(ridx) * w).reshape(len(ridx), w)
            sbuf[:] = array[sidx].reshape(len(sidx), w)
            self.comm.Sendrecv(sbuf, dest=self.nbr[send_side], sendtag=10 + send_side,
                               recvbuf=rbuf, source=self.nbr[recv_side], recvtag=10 + send_side)
            if len(ridx):
                array[ridx] += rbuf.reshape(array[ridx].shape)
