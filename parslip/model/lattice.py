"""Geometry of the two triangular lattices and their global numbering.

Responsible for where every node is, which block it belongs to, its six
neighbour slots, the node sets the boundary conditions act on, and the
interface sites.  Nothing here knows about ranks: the decomposition asks for
the nodes of a column range and gets them in global order.

Layout (units of a; h = sqrt(3)/2 is the row height):

    top block    rows 0..Rt-1, columns c0_t .. c0_t+Ct-1, y = (Rb-1) h + delta0 + r h
    bottom block rows 0..Rb-1, columns 0 .. Cb-1,         y = r h

The substrate is "elastic" (a bottom Born lattice of Rb rows whose row 0 AB
is fixed), "rigid" (one row of fixed interface sites at their reference
positions: the k_n -> infinity limit; it holds no degrees of freedom and is
not numbered, so output files hold the top block only) or absent (a free
block, ``bottom_rows = 0``).

A node in global column c and row r sits at x = c + offset(r), where offset
is 0 on both interface rows (bottom row Rb-1, top row 0) and alternates by
1/2 away from them, so each top interface node faces a bottom one at the
same x across the gap delta0.  Global node ids run column by column, and in
a column bottom block first, rows ascending: the nodes of a column range are
therefore a contiguous id range, which makes every slab's slice of an output
dataset contiguous.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .physics import ROW_HEIGHT

BOTTOM, TOP = 0, 1

# Neighbour slots k = 0..5 at angles k*60 degrees: (dx, dy) in units of a.  The values are
# (cos, sin)(k pi/3) as libm rounds them (an |entry| below 1e-15 set to 0), written out so that no
# host's trigonometry enters the set-up: NumPy's vector cos differs in the last bit between CPUs.
DIRECTIONS = np.array([[1.0, 0.0],
                       [0.5000000000000001, 0.8660254037844386],
                       [-0.4999999999999998, 0.8660254037844387],
                       [-1.0, 0.0],
                       [-0.5000000000000004, -0.8660254037844384],
                       [0.5000000000000001, -0.8660254037844386]])

# Node kinds for the boundary conditions.
FREE, FIXED, DRIVEN = 0, 1, 2


@dataclass(frozen=True)
class Block:
    rows: int
    cols: int
    col0: int          # global column of the block's first node
    y0: float          # y of row 0
    parity: int        # offset(r) = 0.5 * ((r + parity) % 2)

    def offset(self, r):
        return 0.5 * ((np.asarray(r) + self.parity) % 2)


class Lattice:
    """Global description of the bottom block (substrate) and top block.

    ``bottom_rows = 0`` gives a single free block (used by the wave tests).
    """

    def __init__(self, top_rows: int, top_cols: int, bottom_rows: int, bottom_cols: int,
                 delta0: float = 0.5, substrate: str = "elastic"):
        self.delta0 = delta0
        if bottom_rows == 0:
            substrate = "none"
        self.substrate = substrate
        self.rigid = substrate == "rigid"
        if substrate == "rigid":
            bottom_rows = 1             # the fixed row of interface sites
        if bottom_rows > 0:
            self.blocks = (
                Block(bottom_rows, bottom_cols, 0, 0.0, (bottom_rows - 1) % 2),
                Block(top_rows, top_cols, (bottom_cols - top_cols) // 2,
                      (bottom_rows - 1) * ROW_HEIGHT + delta0, 0),
            )
            self.ncols = bottom_cols
        else:
            self.blocks = (Block(0, 0, 0, 0.0, 0), Block(top_rows, top_cols, 0, 0.0, 0))
            self.ncols = top_cols
        self.has_interface = bottom_rows > 0
        # Blocks whose nodes are degrees of freedom, numbered and written out.
        self.numbered = (not self.rigid and bottom_rows > 0, True)
        cols = np.arange(self.ncols)
        self.col_count = np.zeros(self.ncols, np.int64)
        for bi, b in enumerate(self.blocks):
            if self.numbered[bi]:
                self.col_count += np.where((cols >= b.col0) & (cols < b.col0 + b.cols), b.rows, 0)
        self.col_start = np.concatenate([[0], np.cumsum(self.col_count)])
        self.n_nodes = int(self.col_start[-1])

    # ---------------------------------------------------------------- sizes --
    @property
    def top(self) -> Block:
        return self.blocks[TOP]

    @property
    def bottom(self) -> Block:
        return self.blocks[BOTTOM]

    @property
    def contact_length(self) -> float:
        """l = top_cols * a: each interface node stands for one spacing of contact."""
        return float(self.top.cols)

    @property
    def n_top_sites(self) -> int:
        return self.top.cols if self.has_interface else 0

    @property
    def n_bottom_sites(self) -> int:
        return self.bottom.cols if self.has_interface else 0

    # ----------------------------------------------------------- numbering --
    def gid(self, block, row, col):
        """Global id of (block, row, global column); -1 where no such node."""
        block, row, col = np.broadcast_arrays(np.asarray(block), np.asarray(row), np.asarray(col))
        out = np.full(block.shape, -1, np.int64)
        for bi, b in enumerate(self.blocks):
            if not self.numbered[bi]:
                continue
            m = (block == bi) & (row >= 0) & (row < b.rows) & (col >= b.col0) & (col < b.col0 + b.cols)
            below = 0 if bi == BOTTOM or not self.numbered[BOTTOM] else np.where(
                (col[m] >= self.bottom.col0) & (col[m] < self.bottom.col0 + self.bottom.cols),
                self.bottom.rows, 0)
            out[m] = self.col_start[col[m]] + below + row[m]
        return out

    def nodes_in_columns(self, c0: int, c1: int) -> dict[str, np.ndarray]:
        """All nodes with global column in [c0, c1), ordered by global id."""
        c0, c1 = max(c0, 0), min(c1, self.ncols)
        blk, row, col = [], [], []
        for bi, b in enumerate(self.blocks):
            cols = np.arange(max(c0, b.col0), min(c1, b.col0 + b.cols))
            if not self.numbered[bi] or len(cols) == 0:
                continue
            rr, cc = np.meshgrid(np.arange(b.rows), cols)
            blk.append(np.full(rr.size, bi))
            row.append(rr.ravel())
            col.append(cc.ravel())
        if not blk:
            e = np.zeros(0, np.int64)
            return dict(gid=e, block=e, row=e, col=e, x=np.zeros(0), y=np.zeros(0))
        blk, row, col = (np.concatenate(v).astype(np.int64) for v in (blk, row, col))
        order = np.lexsort((row, blk, col))              # global id order: by column, then block, then row
        blk, row, col = blk[order], row[order], col[order]
        x = np.empty(len(blk))
        y = np.empty(len(blk))
        for bi, b in enumerate(self.blocks):
            m = blk == bi
            x[m] = col[m] + b.offset(row[m])
            y[m] = b.y0 + row[m] * ROW_HEIGHT
        gid = self.col_start[c0] + np.arange(len(blk))
        return dict(gid=gid, block=blk, row=row, col=col, x=x, y=y)

    def neighbour(self, block, row, col, k):
        """(row, col) of neighbour slot k of nodes (block, row, col), vectorised."""
        b = self.blocks[block]
        off = b.offset(row)
        if k == 0:
            return row, col + 1
        if k == 3:
            return row, col - 1
        dr = 1 if k in (1, 2) else -1
        dx = 0.5 if k in (1, 5) else -0.5
        noff = b.offset(row + dr)
        return row + dr, (col + off + dx - noff).astype(np.int64)

    # -------------------------------------------------------- node sets ------
    def kinds(self, nodes: dict[str, np.ndarray], mode: str, rows=None) -> np.ndarray:
        """FIXED for the substrate's bottom row AB, DRIVEN for the driven face: with ``rows`` = (first, last)
        only the face's rows first..last, counted from the interface row 0 (push and pull)."""
        kind = np.full(len(nodes["gid"]), FREE, np.int8)
        if self.has_interface:
            kind[(nodes["block"] == BOTTOM) & (nodes["row"] == 0)] = FIXED
        t = self.top
        top = nodes["block"] == TOP
        if rows and mode in ("push", "pull"):
            top = top & (nodes["row"] >= rows[0]) & (nodes["row"] <= rows[1])
        if mode == "push":      # T-: rear face SP, the first node of every top row
            kind[top & (nodes["col"] == t.col0)] = DRIVEN
        elif mode == "pull":    # T+: front face RQ, the last node of every top row
            kind[top & (nodes["col"] == t.col0 + t.cols - 1)] = DRIVEN
        elif mode == "shear":   # T0: top row SR
            kind[top & (nodes["row"] == t.rows - 1)] = DRIVEN
        return kind

    def driven_in_columns(self, mode: str, rows, c0: int, c1: int) -> int:
        """How many nodes ``kinds`` marks DRIVEN among the global columns c0 <= col < c1, in closed form (no
        node list: ``scene.memory`` counts a rank's before anything is built)."""
        t = self.top
        if mode == "shear":
            return max(min(c1, t.col0 + t.cols) - max(c0, t.col0), 0)
        if mode in ("push", "pull"):
            col = t.col0 if mode == "push" else t.col0 + t.cols - 1
            n = (min(rows[1], t.rows - 1) - rows[0] + 1) if rows else t.rows
            return max(n, 0) if c0 <= col < c1 else 0
        return 0

    def is_top_site(self, nodes) -> np.ndarray:
        return self.has_interface & (nodes["block"] == TOP) & (nodes["row"] == 0)

    def is_bottom_site(self, nodes) -> np.ndarray:
        return self.has_interface & (nodes["block"] == BOTTOM) & (nodes["row"] == self.bottom.rows - 1)

    def top_site_of_col(self, col):
        return np.asarray(col) - self.top.col0

    def loaded(self, nodes) -> np.ndarray:
        """The top row SR, which carries the normal load."""
        return (nodes["block"] == TOP) & (nodes["row"] == self.top.rows - 1)

    def neighbour_gids(self, nodes) -> np.ndarray:
        """Global ids of the six neighbour slots of each node (-1: no bond)."""
        out = np.full((len(nodes["gid"]), 6), -1, np.int64)
        for bi in range(len(self.blocks)):
            m = nodes["block"] == bi
            if not m.any():
                continue
            for k in range(6):
                r, c = self.neighbour(bi, nodes["row"][m], nodes["col"][m], k)
                out[m, k] = self.gid(bi, r, c)
        return out
