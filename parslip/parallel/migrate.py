"""Moving per-node and per-site data between two decompositions, by global id.

Two decompositions of the same lattice differ in their slab bounds (x-columns) and in where each block's
columns stand among them (``Placement``: the sliding block's columns at x-column c + D).  A run moves its
state from one to the next when the slabs follow the block's drift (``engine.simulation``), and its
snapshots and checkpoints between the slabs it computes on and the ones its files are written in (the
slabs of no drift, whose nodes are one contiguous range of global ids per rank).

Each rank sends what it holds to the ranks that own it in the new decomposition and receives from the
ranks that held what it now owns; both sides find each other from the two placements alone (every rank
has both), so no counts travel first, and a rank talks only to the ranks whose slabs overlap its own
(old against new): nothing grows with the rank count.  Data are tables keyed by global node id (NODES)
or by interface site (SITES, site s in the block's column col0 + s), each with columns of any shape whose
first axis runs along the keys; what a rank receives comes back sorted by key.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..model.lattice import BOTTOM, TOP
from .layout import _clip, owner_of, slab_columns

# bounds: x-column slab bounds; offsets: (0, D), the x-column offset of each block's columns.
Placement = namedtuple("Placement", "bounds offsets")
NODES, SITES = "nodes", "sites"
TAG = 11


def block_columns(lattice, placement: Placement, p: int, b: int) -> tuple[int, int]:
    """Global columns [lo, hi) of block b that rank p owns under ``placement``."""
    blk = lattice.blocks[b]
    lo, hi = slab_columns(lattice, placement.bounds, p, b, placement.offsets[b])
    return _clip(lo, hi, blk.col0, blk.col0 + blk.cols)


def _owners(lattice, placement: Placement, kind: str, keys: np.ndarray) -> np.ndarray:
    """The rank that owns each key under ``placement``."""
    if kind == SITES:
        block = np.full(len(keys), TOP)
        col = np.asarray(keys, np.int64) + lattice.top.col0
    else:
        block, _, col = lattice.locate(keys)
    x = col + np.asarray(placement.offsets)[block]
    return owner_of(placement.bounds, x)


def _overlap(lattice, a: Placement, p: int, b: Placement, q: int) -> bool:
    """Whether rank p under ``a`` and rank q under ``b`` own columns in common, in either block."""
    for blk in (BOTTOM, TOP):
        if lattice.blocks[blk].rows == 0 or not lattice.numbered[blk]:
            continue
        lo1, hi1 = block_columns(lattice, a, p, blk)
        lo2, hi2 = block_columns(lattice, b, q, blk)
        if min(hi1, hi2) > max(lo1, lo2):
            return True
    return False


def _partners(lattice, mine: Placement, rank: int, other: Placement) -> list[int]:
    """The ranks that own, under ``other``, columns this rank owns under ``mine``."""
    found = set()
    for blk in (BOTTOM, TOP):
        if lattice.blocks[blk].rows == 0 or not lattice.numbered[blk]:
            continue
        lo, hi = block_columns(lattice, mine, rank, blk)
        if hi <= lo:
            continue
        first, last = owner_of(other.bounds, np.array([lo, hi - 1]) + other.offsets[blk])
        found.update(range(int(first), int(last) + 1))
    return sorted(p for p in found if _overlap(lattice, mine, rank, other, p))


def redistribute(comm, lattice, old: Placement, new: Placement, tables: dict) -> dict:
    """Collective over ``comm``: ``tables`` {name: (kind, keys, {column: array})} held under ``old`` become
    those this rank owns under ``new``, keys ascending.  Without a communicator (one rank) they are returned
    as they are, sorted."""
    rank = comm.Get_rank() if comm is not None else 0
    parts = {name: [] for name in tables}
    requests = []
    outgoing = _partners(lattice, old, rank, new) if comm is not None else [rank]
    owners = {name: _owners(lattice, new, kind, keys) if comm is not None else np.zeros(len(keys), np.int64)
              for name, (kind, keys, _) in tables.items()}
    for d in outgoing:
        msg = {}
        for name, (kind, keys, cols) in tables.items():
            m = owners[name] == d
            msg[name] = (keys[m], {c: a[m] for c, a in cols.items()})
        if d == rank:
            for name, part in msg.items():
                parts[name].append(part)
        else:
            requests.append(comm.isend(msg, dest=d, tag=TAG))
    if comm is not None:
        for s in _partners(lattice, new, rank, old):
            if s == rank:
                continue
            msg = comm.recv(source=s, tag=TAG)
            for name, part in msg.items():
                parts[name].append(part)
        for r in requests:
            r.wait()
    out = {}
    for name, (kind, keys, cols) in tables.items():
        got = parts[name]
        k = np.concatenate([g[0] for g in got]) if got else keys[:0]
        order = np.argsort(k, kind="stable")
        out[name] = (kind, k[order], {c: (np.concatenate([g[1][c] for g in got]) if got else a[:0])[order]
                                      for c, a in cols.items()})
    return out
