"""Who owns which columns, which halo copies each rank keeps, and what travels between ranks.

Pure: no MPI, no numba.  Everything here can be tested by drawing it.

The lattice is cut in x into slabs of whole global columns, balanced by an
estimate of the time each column costs (``column_cost``).  Each block (the
substrate, the sliding block) is stored per rank as 2D arrays [rows, columns]
with rows along x; row r of block b keeps the columns

    OWNED  [c0, c1) of the rank, clipped to the block, and
    HALO   the columns within h(b, r) of the slab, clipped to the block,

with h = 1 for bulk rows (a bond spans at most one column) and wider halos
on the two interface rows (``Reach``): the sliding block's bottom row must
see the substrate sites its nodes have slid over, and the substrate's top
row the block's nodes slid over it.  A halo may reach past the neighbouring
slab into slabs further away: the exchange plan lists every peer whose
OWNED columns a rank keeps as HALO, not just its LEFT and RIGHT neighbours,
so slabs may be narrower than the interface slip (multi-hop halos).

What travels every step: the positions of the HALO copies, and the bond
state of the HALO copies of the block's interface sites (interface bonds
are owned by the rank that owns their top node).

Arrays carry one ghost row above and below and one ghost column on each side
(``PAD``), never written and zero: a node at a block's edge reads its missing
neighbours there and weighs them by 0, so edges need no branches.  Task rows
and columns, and exchange segments, are given as array indices (with the pad).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from ..model.lattice import BOTTOM, TOP, Lattice

# The codes the compiled loop reads (the pad, the row kinds, the task fields, the phases) live apart, in
# ``parallel.codes``, so that the loop's compiled code does not depend on this module's bookkeeping.
from .codes import (ALL_BONDS, EARLY, END, EXTRA_BOTTOM, EXTRA_NONE, EXTRA_TOP, FULL, LATE, MASKED, NO_DOWN,  # noqa: F401
                    NO_UP, NODES, PAD, ROWS, SEARCH_MARGIN, TASK_DTYPE, TASK_FIELDS)

LEFT, RIGHT = 0, 1
SIDES = (LEFT, RIGHT)
OWNED, HALO = "owned", "halo"

BULK_REACH = 1
# Row segments up to this many nodes run node by node (a vectorised loop's set-up costs more).
SHORT = 4

# Measured cost of one column, in node updates (the phase times of `parslip bench`: the interface phase
# over the stencil phase, per site and per node):
# a bulk node costs 1; each interface site adds the bond update and the
# re-bonding logic, which costs about SITE_COST node updates per step.
SITE_COST = 12.0


@dataclass(frozen=True)
class Drift:
    """Where the interface rows stand, as the slabs and halos are built for them (a).

    shift     D: the block's columns are placed at x-columns c + D when the lattice is cut into slabs, so each
              rank's block columns sit over its own substrate columns however far the block has slid (the
              block's slabs follow the drift; nodes migrate between ranks by global id when D changes)
    top       (lo, hi): the range that u_x - D of the block's interface sites may take, skin included
    bottom    (lo, hi): the range that u_x of the substrate's interface sites may take, skin included
    """
    shift: int = 0
    top: tuple = (0.0, 0.0)
    bottom: tuple = (0.0, 0.0)
    skin: tuple = (0.0, 0.0, 0.0, 0.0)     # the room (a) each edge had when the box was made: top hi, top lo,
                                           # bottom hi, bottom lo (the loop's drift slots' order)

    @property
    def edges(self) -> tuple:
        """The box's edges, outward, in the drift slots' order: top hi, -top lo, bottom hi, -bottom lo (a)."""
        return self.top[1], -self.top[0], self.bottom[1], -self.bottom[0]

    @property
    def extent(self) -> float:
        """The widest relative slip (a) the box allows between a block site and a substrate site."""
        return max(self.top[1] - self.bottom[0], self.bottom[1] - self.top[0], 0.0)


@dataclass(frozen=True)
class Reach:
    """Halo widths in columns of the two interface rows, from the interface geometry and the slip they serve.

    Every distance an interface update depends on is a distance in current x, wherever the substrate's
    sites have drifted from their columns:
    link = ceil(max(delta_b, R + SEARCH_MARGIN)): how far, in a, one top-bottom interaction reaches (a bond
        breaks at length delta_b; a free site looks at the substrate sites within R + SEARCH_MARGIN of it, R
        the re-bonding length).
    An exact bond update of a node needs the block's interface nodes within 4 links and the substrate sites
    within 3 links of it; a rank needs exact updates for its own nodes and for the block's nodes bonded to
    its own substrate sites (one more link).  So the block's interface row must be stored over the current x
    of the rank's own sites (both rows) plus ``top_cover`` = 5 links on each side, and the substrate's over
    them plus ``bottom_cover`` = 4 links.

    With a drift box (``Drift``: the block's sites at x-column c + D + [t_lo, t_hi], the substrate's at
    c + [b_lo, b_hi]) a rank owning x-columns [c0, c1) has its own sites within
    [c0 + min(t_lo, b_lo), c1 - 1 + max(t_hi, b_hi)], and covers them when its halos are, in columns,

        top    (left, right) = (t_hi - min(t_lo, b_lo) + 5 link,  max(t_hi, b_hi) - t_lo + 5 link + 1)
        bottom (left, right) = (b_hi - min(t_lo, b_lo) + 4 link,  max(t_hi, b_hi) - b_lo + 4 link + 1)

    (``drift_reach``).  With an explicit slip reach U (``interface.slip_reach``: the relative slip bound,
    no shift, no rebuild) both sides are U + 5 link + 1 and U + 4 link + 1 (``interface_reach``).  The
    loop checks every step that the halo covers these distances in the current (slid) positions of both
    rows, and stops the run if not.
    """
    slip: float                 # the relative slip (a) the widths serve
    link: int
    top: tuple                  # (left, right) halo columns of the block's interface row
    bottom: tuple               # (left, right) halo columns of the substrate's interface row
    drift: Drift | None = None  # the drift box the widths serve; None: fixed (an explicit slip reach)

    @property
    def top_cover(self) -> int:
        """Distance (a) beyond the rank's interest the block's interface row must cover."""
        return 5 * self.link

    @property
    def bottom_cover(self) -> int:
        return 4 * self.link

    @property
    def widest(self) -> int:
        """The widest interface halo (columns): how far a rank's stored columns reach beyond its slab."""
        return max(*self.top, *self.bottom, BULK_REACH)


def link_of(rebond_length: float, delta_b: float) -> int:
    """One top-bottom interaction's reach in whole a (``Reach``)."""
    return int(math.ceil(max(delta_b, rebond_length + SEARCH_MARGIN)))


def interface_reach(rebond_length: float, delta_b: float, slip: float) -> Reach:
    """Fixed, symmetric halos that serve a relative slip of at most ``slip`` a (``interface.slip_reach``)."""
    link = link_of(rebond_length, delta_b)
    u = int(math.ceil(slip))
    return Reach(slip=slip, link=link, top=(u + 5 * link + 1,) * 2, bottom=(u + 4 * link + 1,) * 2)


def _outward(v: float, quanta: int) -> float:
    """v rounded up to the next multiple of 1/quanta."""
    return math.ceil(v * quanta) / quanta


def start_box(skin: tuple) -> Drift:
    """The drift box before anything has slid: ``skin`` = (behind, ahead) a around no drift."""
    behind, ahead = skin
    return Drift(0, (-behind, ahead), (-behind, ahead), (ahead, behind, ahead, behind))


def follow_box(drift: Drift, extremes, growth, skin: tuple, quanta: int) -> Drift:
    """The drift box a rebuild makes from the agreed drift: ``extremes`` the interface rows' outward extremes
    relative to ``drift.shift`` (a: top hi, -top lo, bottom hi, -bottom lo), ``growth`` their growth over the
    last agreement interval (a, same order), ``skin`` = (behind, ahead) a.

    The new shift D centres the block's interface sites over the substrate's (the middle of its range less
    the middle of the substrate's, rounded), so each rank's block columns sit over its own substrate columns;
    each edge then gets its skin, ahead or behind the drive's direction (+x), widened to four times its
    edge's growth so that a fast slip is not rebuilt at every agreement; edges on multiples of 1/quanta a."""
    t_hi, t_lo = extremes[0] + drift.shift, -extremes[1] + drift.shift
    b_hi, b_lo = extremes[2], -extremes[3]
    shift = int(round(0.5 * (t_lo + t_hi) - 0.5 * (b_lo + b_hi)))
    behind, ahead = skin
    room = tuple(max(s, 4.0 * g) for s, g in zip((ahead, behind, ahead, behind), growth))
    top = (-_outward(-(t_lo - shift - room[1]), quanta), _outward(t_hi - shift + room[0], quanta))
    bottom = (-_outward(-(b_lo - room[3]), quanta), _outward(b_hi + room[2], quanta))
    return Drift(shift, top, bottom, room)


def drift_reach(link: int, drift: Drift) -> Reach:
    """The halos that cover the drift box ``drift`` (``Reach``)."""
    (tl, th), (bl, bh) = drift.top, drift.bottom
    lo, hi = min(tl, bl), max(th, bh)
    c = math.ceil
    return Reach(slip=drift.extent, link=link, drift=drift,
                 top=(c(th - lo) + 5 * link, c(hi - tl) + 5 * link + 1),
                 bottom=(c(bh - lo) + 4 * link, c(hi - bl) + 4 * link + 1))


def column_cost(lattice: Lattice, shift: int = 0) -> np.ndarray:
    """Estimated time per step of each x-column, in node updates, with the block's columns placed at
    x-columns c + ``shift`` (those beyond the lattice's ends at its first or last column)."""
    cost = np.zeros(lattice.ncols)
    for b, blk in enumerate(lattice.blocks):
        if not lattice.numbered[b] or blk.rows == 0:
            continue
        x = np.clip(np.arange(blk.col0, blk.col0 + blk.cols) + (shift if b == TOP else 0), 0, lattice.ncols - 1)
        per = blk.rows + (SITE_COST if b == TOP and lattice.has_interface else 0.0)
        np.add.at(cost, x, per)
    return cost


def partition(col_cost: np.ndarray, nranks: int) -> np.ndarray | None:
    """Column boundaries [b0 = 0, b1, ..., bP = ncols] balancing the cost per slab.

    Boundary k is the column where the cumulative cost is nearest k/P of the
    total, kept at least one column from its neighbours.  None when there are
    fewer columns than ranks.
    """
    ncols = len(col_cost)
    if nranks > ncols:
        return None
    cum = np.concatenate([[0.0], np.cumsum(col_cost)])
    bounds = [0]
    for k in range(1, nranks):
        target = cum[-1] * k / nranks
        c = int(np.searchsorted(cum, target, side="left"))
        if c > 0 and target - cum[c - 1] < cum[c] - target:
            c -= 1
        c = max(c, bounds[-1] + 1)
        c = min(c, ncols - (nranks - k))
        bounds.append(c)
    bounds.append(ncols)
    return np.array(bounds, np.int64)


def _clip(lo: int, hi: int, b0: int, b1: int) -> tuple[int, int]:
    lo, hi = max(lo, b0), min(hi, b1)
    return (lo, hi) if hi > lo else (b0, b0)


@dataclass
class BlockLayout:
    """One block on one rank: rows x columns stored, which of them are OWNED, per row."""
    rows: int
    span: tuple                 # global columns [bc0, bc1) of the block
    base: int                   # global column of array column 0 (a ghost column)
    width: int                  # array columns: the stored ones and a ghost column on each side
    owned: np.ndarray           # [rows, 2] global [lo, hi) owned per row (lo == hi: none)
    stored: np.ndarray          # [rows, 2] global [lo, hi) stored per row
    integrated: np.ndarray      # [rows] bool: rows the loop advances (not fixed rows)
    parity: int                 # row r has x offset 0.5 * ((r + parity) % 2)

    def shift(self, r: int) -> int:
        """s(r): the up/down neighbours of column c are c - 1 + s and c + s."""
        return (r + self.parity) % 2

    def j(self, c):
        """Array column of global column c."""
        return c - self.base

    @staticmethod
    def prow(r):
        """Array row of block row r."""
        return r + PAD

    @property
    def shape(self) -> tuple[int, int]:
        return self.rows + 2 * PAD, self.width


@dataclass
class Segment:
    block: int
    row: int
    lo: int                     # global columns [lo, hi)
    hi: int


@dataclass
class Peer:
    rank: int
    send: list = field(default_factory=list)       # Segments of my OWNED columns the peer keeps as HALO
    recv: list = field(default_factory=list)       # Segments of the peer's OWNED columns I keep as HALO
    send_sites: list = field(default_factory=list)  # (lo, hi) global columns of interface bond state
    recv_sites: list = field(default_factory=list)


@dataclass
class Layout:
    """One rank's view of the decomposition.

    ``bounds`` cut the x-columns into slabs; block b's column c stands at x-column c + ``offsets[b]`` (the
    drift box's shift for the sliding block, 0 for the substrate), so each block's OWNED columns are the
    rank's slab moved back by its offset (``block_columns``)."""
    rank: int
    size: int
    bounds: np.ndarray
    reach: Reach | None
    blocks: tuple               # BlockLayout for BOTTOM, TOP (BOTTOM has rows = 0 for a free block)
    peers: list
    tasks: np.ndarray           # [ntasks] of TASK_DTYPE: the row schedule of one step
    offsets: tuple = (0, 0)     # x-column offset of each block's columns (BOTTOM, TOP)

    @property
    def col_range(self) -> tuple[int, int]:
        """The rank's slab in x-columns; with no offset, its global columns in both blocks."""
        return int(self.bounds[self.rank]), int(self.bounds[self.rank + 1])

    def block_columns(self, b: int) -> tuple[int, int]:
        """Global columns [lo, hi) of block b this rank owns (lo == hi: none)."""
        lo, hi = self.blocks[b].owned[0] if self.blocks[b].rows else (0, 0)
        return int(lo), int(hi)

    def owned_sites(self) -> tuple[int, int]:
        """Global columns [lo, hi) of the block's interface sites this rank owns."""
        return self.block_columns(TOP)


def slab_columns(lattice: Lattice, bounds: np.ndarray, p: int, b: int, offset: int) -> tuple[int, int]:
    """Global columns [lo, hi) of block b in rank p's slab: its x-columns moved back by the block's
    ``offset``, the first slab reaching back and the last reaching on to the block's ends (a block slid past
    the substrate's ends stays with the end ranks).  Not clipped to the block: a rank stores a block's halo
    next to its slab even where it owns none of the block's columns."""
    blk = lattice.blocks[b]
    last = len(bounds) - 2
    lo = int(bounds[p]) - offset
    hi = int(bounds[p + 1]) - offset
    if p == 0:
        lo = min(lo, blk.col0)
    if p == last:
        hi = max(hi, blk.col0 + blk.cols)
    return lo, hi


def owner_of(bounds: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The rank whose slab holds x-column x (x beyond the ends: the end ranks)."""
    return np.clip(np.searchsorted(bounds, x, side="right") - 1, 0, len(bounds) - 2)


def _halo(lattice: Lattice, b: int, r: int, reach: Reach | None) -> tuple[int, int]:
    """(left, right) halo columns of row r of block b."""
    if reach is not None and lattice.has_interface:
        if b == TOP and r == 0:
            return max(reach.top[0], BULK_REACH), max(reach.top[1], BULK_REACH)
        if b == BOTTOM and r == lattice.bottom.rows - 1:
            return max(reach.bottom[0], BULK_REACH), max(reach.bottom[1], BULK_REACH)
    return BULK_REACH, BULK_REACH


def _block_layout(lattice: Lattice, b: int, c0: int, c1: int, reach: Reach | None, serial: bool) -> BlockLayout:
    """Block b on a rank whose slab holds the block's columns [c0, c1) (``slab_columns``)."""
    blk = lattice.blocks[b]
    span = (blk.col0, blk.col0 + blk.cols)
    owned = np.zeros((blk.rows, 2), np.int64)
    stored = np.zeros((blk.rows, 2), np.int64)
    for r in range(blk.rows):
        owned[r] = _clip(c0, c1, *span)
        h_lo, h_hi = (0, 0) if serial else _halo(lattice, b, r, reach)
        stored[r] = _clip(c0 - h_lo, c1 + h_hi, *span)
    nonempty = stored[:, 1] > stored[:, 0]
    base = (int(stored[nonempty, 0].min()) if nonempty.any() else span[0]) - PAD
    top = (int(stored[nonempty, 1].max()) if nonempty.any() else span[0]) + PAD
    integrated = np.ones(blk.rows, bool)
    if b == BOTTOM and blk.rows:
        integrated[0] = False          # the fixed row AB, or the rigid substrate's only row
    return BlockLayout(rows=blk.rows, span=span, base=base, width=top - base, owned=owned, stored=stored,
                       integrated=integrated, parity=blk.parity)


def _intersect(a, b) -> tuple[int, int] | None:
    lo, hi = max(a[0], b[0]), min(a[1], b[1])
    return (int(lo), int(hi)) if hi > lo else None


def _mask(blk: BlockLayout, r: int, c: int) -> int:
    """Bonds present at node (r, global column c) of a block."""
    bc0, bc1 = blk.span
    s = blk.shift(r)
    m = 0
    present = (
        c + 1 < bc1,                                     # right
        r + 1 < blk.rows and c + s < bc1,                # up-right
        r + 1 < blk.rows and c - 1 + s >= bc0,           # up-left
        c - 1 >= bc0,                                    # left
        r - 1 >= 0 and c - 1 + s >= bc0,                 # down-left
        r - 1 >= 0 and c + s < bc1,                      # down-right
    )
    for k, p in enumerate(present):
        m |= int(p) << k
    return m


def _tasks(lattice: Lattice, blocks, peers, mode: str, overlap: bool = False) -> np.ndarray:
    """The row schedule: every OWNED node of an integrated row in exactly one task.

    Interior columns of a row run in one vectorised loop of its kind (FULL,
    NO_UP, NO_DOWN); the first and last column of a block, where bonds are
    missing, and segments of at most SHORT nodes run as MASKED single nodes.
    Both kernels form the same differences and sums in the same order, so a
    node gets the same bits whichever runs it, and the cut does not matter.  A task is ``early`` when a peer
    keeps some of its nodes as HALO: the loop runs early tasks first, sends,
    and runs the rest while the messages travel.  Without ``overlap`` a rank with peers runs every task
    early (whole rows, then the exchange).  Consecutive rows over the same columns then merge into one task
    (``_merge_rows``), so a cut costs a column task per block rather than a task per row.
    """
    rows = []
    for b in (BOTTOM, TOP):
        blk = blocks[b]
        bc0, bc1 = blk.span
        for r in range(blk.rows):
            if not blk.integrated[r]:
                continue
            lo, hi = (int(v) for v in blk.owned[r])
            if hi <= lo:
                continue
            # Columns a peer keeps: left- and right-anchored parts of the owned range.
            e_lo, e_hi = lo, hi
            for p in peers:
                for sg in p.send:
                    if sg.block == b and sg.row == r:
                        if sg.lo == lo:
                            e_lo = max(e_lo, sg.hi)
                        if sg.hi == hi:
                            e_hi = min(e_hi, sg.lo)
            if peers and not overlap:
                e_lo, e_hi = hi, lo          # every column early, the row uncut
            extra = EXTRA_NONE
            if lattice.has_interface and b == TOP and r == 0:
                extra = EXTRA_TOP
            if lattice.has_interface and not lattice.rigid and b == BOTTOM and r == blk.rows - 1:
                extra = EXTRA_BOTTOM
            load = int(b == TOP and r == blk.rows - 1)
            row_drive = int(mode == "shear" and b == TOP and r == blk.rows - 1)
            has_up, has_dn = r + 1 < blk.rows, r > 0
            kind = FULL if has_up and has_dn else (NO_UP if has_dn else NO_DOWN)
            if not has_up and not has_dn:
                kind = MASKED          # a one-row block: every node on its own

            def early(c_lo, c_hi):
                return int(c_lo < e_lo or c_hi > e_hi)

            def col_drive(c):
                return int(row_drive or (b == TOP and ((mode == "push" and c == bc0) or
                                                      (mode == "pull" and c == bc1 - 1))))

            cuts = sorted({lo, hi, max(lo, min(hi, bc0 + 1)), max(lo, min(hi, bc1 - 1)),
                           max(lo, min(hi, e_lo)), max(lo, min(hi, e_hi))})
            for c_lo, c_hi in zip(cuts[:-1], cuts[1:]):
                if c_hi <= c_lo:
                    continue
                if kind == MASKED or c_hi - c_lo <= SHORT:
                    # Block edges, and segments too short to pay for a vectorised loop: node by node.
                    # With every bond of its row present, the single-node kernel gives the same bits.
                    for c in range(c_lo, c_hi):
                        m = _mask(blk, r, c)
                        rows.append((b, blk.prow(r), blk.j(c), 1, MASKED, m, extra, load, col_drive(c),
                                     early(c, c + 1), blk.shift(r), 1, m))
                else:
                    rows.append((b, blk.prow(r), blk.j(c_lo), c_hi - c_lo, kind, ALL_BONDS, extra, load,
                                 row_drive, early(c_lo, c_hi), blk.shift(r), 1, ALL_BONDS))
    t = np.array([tuple(r) for r in rows], TASK_DTYPE)
    # Grouped by phase (early first), block, then row tasks before single nodes, each by its columns, then
    # rows: consecutive rows over the same columns are neighbours, and merge.
    order = np.lexsort((t["row"], t["n"], t["j0"], t["kind"] == MASKED, t["block"], 1 - t["early"]))
    return _merge_rows(t[order])


def _merge_rows(t: np.ndarray) -> np.ndarray:
    """Tasks of consecutive rows over the same columns merged into one task of several rows (``codes``: rows,
    mask2): the FULL rows of a block (not driven), and the single nodes of a column whose masks alternate with
    the rows' shift.  One task dispatch and the views of a row (``kernels.rect``) where each row was a task:
    about 25 ns a row (``studies.bench.rows``).  The nodes and their kernels' arithmetic do not change."""
    names = t.dtype.names
    same = [names.index(f) for f in ("block", "j0", "n", "kind", "extra", "load", "drive", "early")]
    row, kind, drive, mask, rows, mask2 = (names.index(f) for f in ("row", "kind", "drive", "mask", "rows", "mask2"))
    out = []
    for tk in t.tolist():
        tk = list(tk)
        last = out[-1] if out else None
        if (last is not None and all(last[f] == tk[f] for f in same) and tk[row] == last[row] + last[rows]
                and ((tk[kind] == FULL and not tk[drive]) or tk[kind] == MASKED)):
            if tk[kind] == FULL or last[rows] == 1 or tk[mask] == last[mask if last[rows] % 2 == 0 else mask2]:
                if last[rows] == 1:
                    last[mask2] = tk[mask]
                last[rows] += 1
                continue
        out.append(tk)
    return np.array([tuple(r) for r in out], t.dtype)




def task_ranges(tasks: np.ndarray) -> np.ndarray:
    """ptr[phase, block, ROWS | NODES | END]: the first row task, the first single-node task and the end
    of each phase's (EARLY, LATE) tasks of each block in the sorted schedule."""
    ptr = np.zeros((2, 2, 3), np.int64)
    pos = 0
    for phase in (0, 1):
        for b in (BOTTOM, TOP):
            sel = (tasks["early"] == 1 - phase) & (tasks["block"] == b)
            n_rows = int((sel & (tasks["kind"] != MASKED)).sum())
            n_all = int(sel.sum())
            ptr[phase, b] = [pos, pos + n_rows, pos + n_all]
            pos += n_all
    return ptr


def build_layout(lattice: Lattice, rank: int, size: int, reach: Reach | None, mode: str = "none",
                 cost: np.ndarray | None = None, bounds: np.ndarray | None = None, overlap: bool = False) -> Layout:
    """The decomposition seen from ``rank`` of ``size``.  Raises ConfigError if it cannot be cut.

    The sliding block's columns stand at x-columns c + D (D = ``reach.drift.shift``, 0 without a drift box);
    the slabs balance the cost of that placement (``column_cost``) unless ``bounds`` are given.  Only the
    ranks whose slabs lie within the widest halo of this rank's are looked at: the set-up of one rank does
    not grow with the rank count.  With ``overlap`` (``run.overlap``) rows are cut so that the columns peers
    keep are updated and sent first (``_tasks``)."""
    shift = reach.drift.shift if reach is not None and reach.drift is not None else 0
    offsets = (0, shift)
    if bounds is None:
        bounds = slab_bounds(lattice, size, shift, cost)
    serial = size == 1

    def blocks_of(p):
        return tuple(_block_layout(lattice, b, *slab_columns(lattice, bounds, p, b, offsets[b]), reach, serial)
                     for b in (BOTTOM, TOP))

    mine = blocks_of(rank)
    peers = []
    reach_cols = (reach.widest if reach is not None else BULK_REACH) + 1
    first, last = owner_of(bounds, np.array([bounds[rank] - reach_cols, bounds[rank + 1] - 1 + reach_cols]))
    for p in range(int(first), int(last) + 1):
        if p == rank:
            continue
        peer = _peer(lattice, p, mine, blocks_of(p))
        if peer.send or peer.recv:
            peers.append(peer)
    tasks = _tasks(lattice, mine, peers, mode, overlap)
    return Layout(rank=rank, size=size, bounds=bounds, reach=reach, blocks=mine, peers=peers, tasks=tasks,
                  offsets=offsets)


def _peer(lattice: Lattice, p: int, mine, theirs) -> Peer:
    """What this rank sends rank p (its OWNED columns p keeps as HALO) and receives from it, per block row."""
    peer = Peer(p)
    for b in (BOTTOM, TOP):
        if b == BOTTOM and lattice.rigid:
            continue              # the rigid substrate never moves: nothing to send
        for r in range(mine[b].rows):
            s = _intersect(mine[b].owned[r], theirs[b].stored[r])
            if s:
                peer.send.append(Segment(b, r, *s))
                if b == TOP and r == 0 and lattice.has_interface:
                    peer.send_sites.append(s)
            v = _intersect(theirs[b].owned[r], mine[b].stored[r])
            if v:
                peer.recv.append(Segment(b, r, *v))
                if b == TOP and r == 0 and lattice.has_interface:
                    peer.recv_sites.append(v)
    return peer


def owned_site_counts(lattice: Lattice, bounds: np.ndarray, shift: int = 0) -> np.ndarray:
    """Interface sites of the block each rank owns, from the slab bounds and the block's shift alone (every
    rank can compute every rank's count: the frame buffer is sized from it, the same on all ranks)."""
    if not lattice.has_interface:
        return np.zeros(len(bounds) - 1, np.int64)
    lo, hi = lattice.top.col0, lattice.top.col0 + lattice.top.cols
    a = np.asarray(bounds[:-1], np.int64) - shift
    z = np.asarray(bounds[1:], np.int64) - shift
    a[0], z[-1] = min(a[0], lo), max(z[-1], hi)
    return np.clip(np.minimum(z, hi) - np.maximum(a, lo), 0, None).astype(np.int64)


def slab_bounds(lattice: Lattice, size: int, shift: int = 0, cost=None) -> np.ndarray:
    """The slabs' column bounds on ``size`` ranks for the block at shift ``shift`` (``partition`` of
    ``column_cost``, or of ``cost``); ConfigError (one line) when there are fewer columns than ranks."""
    bounds = partition(column_cost(lattice, shift) if cost is None else cost, size)
    if bounds is None:
        raise ConfigError(f"ranks = {size}: the lattice has {lattice.ncols} columns and every slab needs at "
                          f"least one; accepted: 1 to {lattice.ncols} ranks")
    return bounds


def max_ranks(lattice: Lattice) -> int:
    """Every rank owns at least one column; halos reach across as many slabs as they need."""
    return lattice.ncols
