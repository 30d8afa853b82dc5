"""Every rank's share of a decomposition, counted in closed form for all ranks at once.

Pure: no MPI, no layouts.  ``parallel.layout.build_layout`` gives one rank its arrays, its peers and what
travels between them; this module gives the same counts for every rank of a decomposition as arrays over
the ranks, from the slab bounds, the blocks' offsets and the halo widths alone, in time linear in the
columns and the ranks, so that `parslip info --ranks 4096` and the memory prediction never build 4096
layouts.  ``tests/test_follow.py`` checks every count against the layouts themselves.

A block b on rank p (``layout.slab_columns``): its slab's columns [c0, c1) (unclipped), owned
[c0, c1) clipped to the block, and each row stored over [c0 - h_left, c1 + h_right) clipped, with h = 1
for bulk rows and the interface halos (``layout.Reach``) on the interface rows.  A rank receives every
stored column it does not own, and sends each owned column once to every other rank that stores it; each
carries 2 values (x, y) per node, and the block's interface row the bond table's travelling rows per site.

The loop's tasks (``layout._tasks``): each integrated row of a rank's owned columns [lo, hi) is cut at the
block's first and last column (updated with their missing bonds); a piece of at most ``layout.SHORT`` columns
runs node by node (``singles``), a longer one as one vectorised segment (``segments``).  With overlap each
row is also cut where the columns a peer keeps end: counted as one single node per row and side with a peer
(the bulk rows' halo of one column; the interface rows' wider halos are left out).  The schedule runs
consecutive rows over the same columns as one task (``layout._merge_rows``); the counts are of row segments
and nodes, whatever task holds them (the travel model's coefficients are per row segment and per node).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.interface import BONDS
from ..model.lattice import BOTTOM, TOP
from .layout import BULK_REACH, PAD, SHORT


@dataclass
class Counts:
    """Per-rank arrays (index: rank) of one decomposition."""
    nodes: np.ndarray           # OWNED nodes
    sites: np.ndarray           # OWNED interface sites of the sliding block
    sent: np.ndarray            # halo values sent per step
    received: np.ndarray        # halo values received per step
    peers: np.ndarray           # ranks exchanged with per step
    hops: np.ndarray            # slabs to the farthest peer
    cells: tuple                # per block: array cells of its state arrays ((rows + 2 PAD) x width)
    halo_top: np.ndarray        # [ranks, 2] HALO columns (left, right) of the block's interface row
    halo_bottom: np.ndarray     # [ranks, 2] of the substrate's interface row
    segments: np.ndarray        # row segments the loop runs as one vectorised task per step
    singles: np.ndarray         # nodes it runs one by one (block edges, short pieces)

    @property
    def values(self) -> np.ndarray:
        return self.sent + self.received

    @property
    def messages(self) -> np.ndarray:
        return 2 * self.peers


def _slabs(lattice, bounds, b: int, offset: int):
    """Each rank's slab of block b's columns, unclipped (c0, c1) and owned (lo, hi)."""
    blk = lattice.blocks[b]
    c0 = np.asarray(bounds[:-1], np.int64) - offset
    c1 = np.asarray(bounds[1:], np.int64) - offset
    c0[0] = min(c0[0], blk.col0)
    c1[-1] = max(c1[-1], blk.col0 + blk.cols)
    lo = np.clip(c0, blk.col0, blk.col0 + blk.cols)
    hi = np.clip(c1, blk.col0, blk.col0 + blk.cols)
    hi = np.maximum(hi, lo)
    return c0, c1, lo, hi


def _row_classes(lattice, b: int, reach, serial: bool):
    """[(rows, (h_left, h_right), values per column)] of block b: its bulk rows and its interface row."""
    blk = lattice.blocks[b]
    if blk.rows == 0:
        return []
    h1 = (0, 0) if serial else (BULK_REACH, BULK_REACH)
    iface = lattice.has_interface and reach is not None and not serial
    row_if = 0 if b == TOP else blk.rows - 1
    if not iface:
        return [(blk.rows, h1, 2, False)]
    h = reach.top if b == TOP else reach.bottom
    h = (max(h[0], BULK_REACH), max(h[1], BULK_REACH))
    travel = len(BONDS.travel) if b == TOP else 0
    out = [(1, h, 2 + travel, True)]
    if blk.rows > 1:
        out.append((blk.rows - 1, h1, 2, False))
    del row_if
    return out


def _union(intervals, P: int):
    """Each rank's peers (the union of its intervals, less itself) and its farthest peer's distance."""
    peers = np.zeros(P, np.int64)
    hops = np.zeros(P, np.int64)
    for p in range(P):
        spans = sorted((int(a[p]), int(z[p])) for a, z in intervals if z[p] >= a[p])
        count, end, far = 0, -1, 0
        for a, z in spans:
            a = max(a, end + 1)
            if z >= a:
                count += z - a + 1 - (1 if a <= p <= z else 0)
                far = max(far, abs(a - p), abs(z - p))
                end = z
        peers[p], hops[p] = count, far
    return peers, hops


def _tasks(blk, b: int, lo, hi, overlap: bool):
    """Per rank: (segments, single nodes) of block b's integrated rows over owned columns [lo, hi)."""
    rows = blk.rows - (1 if b == BOTTOM else 0)         # the substrate's fixed row is never updated
    a = np.maximum(lo, np.minimum(hi, blk.col0 + 1))
    z = np.maximum(lo, np.minimum(hi, blk.col0 + blk.cols - 1))
    segs = np.zeros(len(lo), np.int64)
    singles = np.zeros(len(lo), np.int64)
    for w in (a - lo, z - a, hi - z):
        segs += w > SHORT
        singles += np.where(w <= SHORT, w, 0)
    if overlap and len(lo) > 1:
        sides = (np.arange(len(lo)) > 0).astype(np.int64) + (np.arange(len(lo)) < len(lo) - 1)
        singles += np.where(hi > lo, sides, 0)
    return rows * segs, rows * singles


def rank_counts(lattice, bounds, reach, offsets=(0, 0), overlap: bool = False) -> Counts:
    """The counts of every rank of the decomposition ``bounds`` (x-column slab bounds), ``offsets`` (the
    x-column offset of each block's columns), ``reach`` (the interface halos) and ``overlap``
    (``run.overlap``: rows cut for the exchange)."""
    P = len(bounds) - 1
    serial = P == 1
    nodes = np.zeros(P, np.int64)
    sites = np.zeros(P, np.int64)
    sent = np.zeros(P, np.int64)
    recv = np.zeros(P, np.int64)
    segments = np.zeros(P, np.int64)
    singles = np.zeros(P, np.int64)
    cells = []
    halos = {TOP: np.zeros((P, 2), np.int64), BOTTOM: np.zeros((P, 2), np.int64)}
    intervals = []              # (first, last) rank arrays: each rank's peers are their union, less itself
    for b in (BOTTOM, TOP):
        blk = lattice.blocks[b]
        if blk.rows == 0:
            cells.append(np.full(P, (blk.rows + 2 * PAD) * 0))
            continue
        c0, c1, lo, hi = _slabs(lattice, bounds, b, offsets[b])
        owned = hi - lo
        seg, one = _tasks(blk, b, lo, hi, overlap and not serial)
        segments += seg
        singles += one
        numbered = lattice.numbered[b]
        if numbered:
            nodes += owned * blk.rows
        if b == TOP and lattice.has_interface:
            sites += owned
        s_lo = np.full(P, np.iinfo(np.int64).max)
        s_hi = np.full(P, np.iinfo(np.int64).min)
        for rows, (hl, hr), per, is_iface in _row_classes(lattice, b, reach, serial):
            st_lo = np.clip(c0 - hl, blk.col0, blk.col0 + blk.cols)
            st_hi = np.maximum(np.clip(c1 + hr, blk.col0, blk.col0 + blk.cols), st_lo)
            nonempty = st_hi > st_lo
            s_lo = np.where(nonempty, np.minimum(s_lo, st_lo), s_lo)
            s_hi = np.where(nonempty, np.maximum(s_hi, st_hi), s_hi)
            if is_iface:
                halos[b][:, 0] = np.where(owned > 0, lo - st_lo, 0)
                halos[b][:, 1] = np.where(owned > 0, st_hi - hi, 0)
            if not numbered or serial:
                continue            # the rigid substrate never moves: nothing travels
            recv += rows * per * ((st_hi - st_lo) - owned)
            # Each column c is stored by the ranks q with c1_q + hr > c and c0_q - hl <= c (its owner among them).
            cols = np.arange(blk.col0, blk.col0 + blk.cols)
            first = np.searchsorted(c1 + hr, cols, side="right")
            last = np.searchsorted(c0 - hl, cols, side="right") - 1
            keepers = np.maximum(last - first + 1, 1) - 1
            per_rank = np.zeros(P, np.int64)
            owner = np.clip(np.searchsorted(hi, cols, side="right"), 0, P - 1)
            np.add.at(per_rank, owner, keepers)
            sent += rows * per * per_rank
            # Peers: the ranks owning columns I store, and those storing columns I own.
            intervals.append((np.searchsorted(hi, st_lo, side="right"), np.searchsorted(lo, st_hi, side="left") - 1))
            mine = owned > 0
            intervals.append((np.where(mine, np.searchsorted(c1 + hr, lo, side="right"), P),
                              np.where(mine, np.searchsorted(c0 - hl, hi, side="left") - 1, -1)))
        width = np.where(s_hi > s_lo, s_hi - s_lo, 0) + 2 * PAD
        cells.append((blk.rows + 2 * PAD) * width)
    peers, hops = _union(intervals, P)
    return Counts(nodes=nodes, sites=sites, sent=sent, received=recv, peers=peers, hops=hops, cells=tuple(cells),
                  halo_top=halos[TOP], halo_bottom=halos[BOTTOM], segments=segments, singles=singles)
