"""One rank's evolving state, and reading or writing it by global node id.

Responsible for the arrays the loop advances (``loop.Levels``, ``loop.Iface``,
the drive's reference) and for every view of them that other parts need in
global numbering: snapshots, checkpoints, tests that compare runs by global
id.  Displacements u from the reference lattice are stored, never absolute
positions, so float32 keeps the strain.

Level ``n % 2`` holds u(n) and level ``(n + 1) % 2`` holds u(n - 1) at step n.
"""
from __future__ import annotations

import numpy as np

from ..io.contract import EVENT_DATASETS
from ..model.lattice import BOTTOM, DIRECTIONS, DRIVEN, TOP
from ..model.physics import DENSITY
from ..parallel.layout import PAD
from ..model.interface import BOND_TABLE, BONDS, KX, KY, PARTNER, X0
from .kernels import interface as ik
from .loop import Drive, Levels


def stiffness_constants(kn: float, kt: float, dt: float, damping) -> np.ndarray:
    """[C k_n, C k_t, C A, C B', C C', B] of ``kernels.stencil``: A = (k_n-k_t)/4 + k_t, B' = sqrt(3)(k_n-k_t)/4,
    C' = 3(k_n-k_t)/4 + k_t; C and B the damped update's factors, and g the bonds' damping gain
    (``model.damping.Damping``), in K_RATE."""
    from .kernels.stencil import K_A, K_B, K_C, K_DAMP, K_N, K_RATE, K_SIZE, K_T
    d = kn - kt
    cf = damping.force_factor(dt)
    k = np.zeros(K_SIZE)
    k[K_N], k[K_T], k[K_A] = cf * kn, cf * kt, cf * (d / 4 + kt)
    k[K_B], k[K_C], k[K_DAMP] = cf * (np.sqrt(3.0) * d / 4), cf * (3 * d / 4 + kt), damping.carry(dt)
    k[K_RATE] = damping.rate_gain(kn, dt)
    return k


def event_record(capacity: int):
    """An empty event record (``kernels.interface.Events``) of ``capacity`` events."""
    return ik.Events(**{name: np.zeros(capacity, EVENT_DATASETS[name][0]) for name in ik.Events._fields
                        if name != "count"}, count=np.zeros(1, np.int64))


def _arena(shapes, dtype) -> list[np.ndarray]:
    """Zeroed C-contiguous arrays of these shapes, carved from one allocation.

    One allocation of several MiB gets huge pages from the allocator (NumPy
    asks the kernel for them), so the whole state costs a few TLB entries.
    Each array starts a different number of cache lines past a 4 KiB boundary:
    the same element of two arrays of one shape then never shares its address
    modulo 4 KiB, which would stall a loop that reads one and writes the other
    on false store-to-load dependences (4K aliasing).
    """
    item = np.dtype(dtype).itemsize
    page = 4096 // item
    sizes = [int(np.prod(sh)) for sh in shapes]
    starts, pos = [], 0
    for k, n in enumerate(sizes):
        pos = -(-pos // page) * page + (k * 192) // item          # next page boundary, then k x 3 cache lines
        starts.append(pos)
        pos += n
    buf = np.zeros(pos + page, dtype)
    base = (-buf.ctypes.data % 4096) // item
    return [buf[base + s:base + s + n].reshape(sh) for s, n, sh in zip(starts, sizes, shapes)]


class State:
    """The arrays of one rank, built from the layout, in float type ``dtype``; room for ``event_capacity``
    bond events (``Simulation`` sizes it and empties it before it can overflow)."""

    def __init__(self, setup, layout, dtype=np.float64, event_capacity: int = 0):
        self.setup, self.layout = setup, layout
        self.dtype = dt = np.dtype(dtype)
        lat, mat = setup.lattice, setup.material
        bl, tl = layout.blocks

        # The bonds' damping takes the bond forces on a field z of its own (``loop.Levels``): whole blocks then.
        zs = [bl.shape] * 2 + [tl.shape] * 2 if setup.damping.rated else [(1, 1)] * 4
        self.levels = Levels(*_arena([bl.shape] * 4 + [tl.shape] * 4, dt), *(np.zeros(z, dt) for z in zs))
        damping = setup.damping
        self.K = np.array([stiffness_constants(mat.kn_bottom, mat.kt_bottom, setup.dt, damping),
                           stiffness_constants(mat.kn_top, mat.kt_top, setup.dt, damping)], dt)

        # Interface ------------------------------------------------------------
        wt, wb = tl.width, bl.width
        # The per-site bond state (``model.interface.BOND_TABLE``): every stored site starts bonded to the
        # substrate site facing it, each other row at its ``initial`` value (x0 = 0).
        bonds = np.zeros((len(BONDS.names), wt), dt)
        for i, row in enumerate(BOND_TABLE):
            if row.initial is not None:
                bonds[i] = row.initial
        bonds[PARTNER] = -1
        reach = layout.reach
        law = setup.law
        if lat.has_interface:
            lo, hi = tl.j(tl.stored[0])
            bonds[PARTNER, lo:hi] = np.arange(lo, hi) + tl.base    # each top site faces the bottom site of its column
            # The sites' own constants, from their global index (the same field on every rank).
            sites = np.arange(lo, hi) + tl.base - lat.top.col0
            for name, values in law.site_values(lat.n_top_sites).items():
                bonds[BONDS.names.index(name), lo:hi] = values[sites]
            br = bl.rows - 1
            blo, bhi = bl.j(bl.stored[br])
            bown0, bown1 = bl.j(bl.owned[br])
            if lat.rigid:                     # a rigid substrate feels no reaction: no owned substrate sites
                bown0 = bown1 = blo
            town0, town1 = tl.j(tl.owned[0])
            geom = ik.Geometry(tbase=tl.base, tlo=lo, thi=hi, town0=town0, town1=town1, bbase=bl.base, blo=blo,
                               bhi=bhi, bown0=bown0, bown1=bown1, brow=bl.prow(br),
                               tfirst=tl.span[0], tlast=tl.span[1] - 1, bcols=lat.bottom.cols, rigid=int(lat.rigid),
                               tcover=reach.top_cover, bcover=reach.bottom_cover)
        else:
            geom = ik.Geometry(*([0] * len(ik.Geometry._fields)))
        consts = ik.Constants(inv_l=dt.type(1.0 / setup.l),
                              traction=dt.type(1.0 / (DENSITY * mat.c_r ** 2)), energy=dt.type(1.0 / mat.c_r ** 2))
        geom = ik.Geometry(*(int(v) for v in geom))
        self.iface = ik.Iface(bonds=bonds, rules=law.rules(dt, setup), claim=np.zeros(wt, np.int64),
                              taken=np.zeros(max(wb, 1), np.int8), ext_x=np.zeros(wt, dt), ext_y=np.zeros(wt, dt),
                              exb_x=np.zeros(max(wb, 1), dt), exb_y=np.zeros(max(wb, 1), dt),
                              zeros=np.zeros(max(wt, wb, 1), dt), geom=geom, consts=consts,
                              counters=np.zeros(2, np.int64), reach=np.full(1, -1, np.int64),
                              events=event_record(event_capacity))

        self._index_owned()

        # Drive -----------------------------------------------------------------
        # The OWNED driven nodes of the top block, in global id order, each with its slot in the drive's
        # force array (``loop.Drive``).
        drive = setup.drive
        d = np.flatnonzero(lat.kinds(self.nodes(), drive.mode, drive.rows) == DRIVEN) if drive.on \
            else np.zeros(0, np.int64)
        self.driven_gid = self.gid[d]
        index = np.full(tl.shape, -1, np.int64)
        index[self.own_prow[d], self.own_j[d]] = np.arange(len(d))
        self.drive = Drive(drive0=np.zeros(tl.shape, dt), index=index, force=np.zeros(len(d), dt))

    # ------------------------------------------------------------ numbering --
    def _index_owned(self):
        """(block, row, local column) of every OWNED node, in global id order (column by column, substrate
        rows first), and the reference positions (a)."""
        lay = self.layout
        nd = self.setup.lattice.nodes_in_block_columns((lay.block_columns(BOTTOM), lay.block_columns(TOP)))
        blk, row, col = nd["block"], nd["row"], nd["col"]
        self.own_block, self.own_row, self.own_col, self.gid = blk, row, col, nd["gid"]
        self.ref_x, self.ref_y = nd["x"], nd["y"]
        bases = np.array([lay.blocks[BOTTOM].base, lay.blocks[TOP].base])
        self.own_j = col - bases[blk] if len(blk) else col
        self.own_prow = row + PAD

    @property
    def n_owned(self) -> int:
        return len(self.gid)

    def nodes(self) -> dict:
        """The OWNED nodes in global id order: gid, block, row, col, and reference x, y (a)."""
        return dict(gid=self.gid, block=self.own_block, row=self.own_row, col=self.own_col, x=self.ref_x,
                    y=self.ref_y)

    def fixed(self) -> np.ndarray:
        """OWNED nodes the loop never moves: the substrate's bottom row AB."""
        lat = self.setup.lattice
        return (self.own_block == BOTTOM) & (self.own_row == 0) if lat.numbered[BOTTOM] else \
            np.zeros(self.n_owned, bool)

    def level(self, n: int):
        """(bx, by, tx, ty) of level n % 2."""
        lv = self.levels
        return (lv.bx0, lv.by0, lv.tx0, lv.ty0) if n % 2 == 0 else (lv.bx1, lv.by1, lv.tx1, lv.ty1)

    def owned_u(self, n: int, dtype=np.float64) -> np.ndarray:
        """u(n) of the OWNED nodes, (n_owned, 2) in global id order (a); in the state's own float type
        (``dtype=self.dtype``) it is bitwise, as a checkpoint needs."""
        bx, by, tx, ty = self.level(n)
        out = np.zeros((self.n_owned, 2), dtype)
        for b, (ax, ay) in ((BOTTOM, (bx, by)), (TOP, (tx, ty))):
            m = self.own_block == b
            out[m, 0] = ax[self.own_prow[m], self.own_j[m]]
            out[m, 1] = ay[self.own_prow[m], self.own_j[m]]
        return out

    def set_owned_u(self, n: int, u: np.ndarray):
        """Write u (n_owned, 2), in global id order, into level n % 2 (OWNED nodes only)."""
        bx, by, tx, ty = self.level(n)
        for b, (ax, ay) in ((BOTTOM, (bx, by)), (TOP, (tx, ty))):
            m = self.own_block == b
            ax[self.own_prow[m], self.own_j[m]] = u[m, 0]
            ay[self.own_prow[m], self.own_j[m]] = u[m, 1]

    # ------------------------------------------------------------ interface --
    def owned_sites(self) -> slice:
        """Local columns of the OWNED top interface sites."""
        g = self.iface.geom
        return slice(g.town0, g.town1)

    def site0(self) -> int:
        """Global index (0 = the block's first column) of the first OWNED interface site."""
        lo, _ = self.layout.owned_sites()
        return lo - self.setup.lattice.top.col0

    def owned_partner(self) -> np.ndarray:
        """The substrate column each OWNED site is bonded to (-1 broken), int64."""
        return self.iface.bonds[PARTNER, self.owned_sites()].astype(np.int64)

    def owned_x0(self) -> np.ndarray:
        return self.iface.bonds[X0, self.owned_sites()].astype(np.float64)

    def owned_bonds(self) -> dict:
        """The rows a checkpoint holds of the OWNED sites' bond state, by name (``model.interface.BONDS``),
        copies in the state's float type."""
        s = self.owned_sites()
        return {name: self.iface.bonds[BONDS.names.index(name), s].copy() for name in BONDS.checkpoint}

    def set_owned_bonds(self, rows: dict):
        """Set the OWNED sites' bond state from rows by name (a checkpoint's); HALO copies follow at the
        next exchange."""
        s = self.owned_sites()
        for name in BONDS.checkpoint:
            self.iface.bonds[BONDS.names.index(name), s] = rows[name]

    def max_top_slip(self, n: int) -> float:
        """max |u_x,top - u_x,bottom| over the OWNED top interface sites at step n (a): how far the block's
        interface has slid relative to the substrate's sites of the same columns (the halo serves that)."""
        bx, _, tx, _ = self.level(n)
        s = self.owned_sites()
        if s.stop <= s.start or not self.setup.lattice.has_interface:
            return 0.0
        g = self.iface.geom
        cols = np.arange(s.start, s.stop) + g.tbase - g.bbase      # the same columns in the substrate's arrays
        held = (cols >= g.blo) & (cols < g.bhi)
        under = np.zeros(len(cols))
        under[held] = bx[g.brow, cols[held]]
        return float(np.max(np.abs(tx[PAD, s].astype(float) - under)))

    # ------------------------------------------------------------- fields ----
    def potential_energy(self, n: int, load: float) -> float:
        """Potential energy of the OWNED part at step n, in m c^2 (``load``: the factor on F_N):
        bulk bonds (``kernels.diagnostics.bond_energy``), interface bonds
        1/2 k_x (x_ij - x0)^2 + 1/2 k_y (y_ij - delta0)^2 on their top node (at the site's k_x: a weakening
        bond's secant is not read here), and the load's -F . u."""
        from .kernels.diagnostics import bond_energy
        e = np.zeros(self.n_owned)
        bond_energy(*self.level(n), self.own_block, self.own_prow, self.own_j, self.block_geometry(),
                    self.stiffness(), DIRECTIONS, e)
        total = float(e.sum())
        lat, sc = self.setup.lattice, self.setup.scene
        if lat.has_interface:
            bx, by, tx, ty = self.level(n)
            g = self.iface.geom
            s = self.owned_sites()
            p = self.owned_partner()
            bonded = p >= 0
            j = np.arange(s.start, s.stop)[bonded]
            i = p[bonded] - g.bbase
            br = g.brow
            dx = (j + g.tbase - p[bonded]) + (tx[PAD, j].astype(float) - bx[br, i])
            law = self.setup.law
            dy = law.delta0 + (ty[PAD, j].astype(float) - by[br, i])
            b = self.iface.bonds
            total += float(np.sum(0.5 * b[KX, j] * (dx - b[X0, j]) ** 2 + 0.5 * b[KY, j] * (dy - law.delta0) ** 2))
            top_row = (self.own_block == TOP) & (self.own_row == lat.top.rows - 1)
            u = self.owned_u(n)
            total -= load * (-sc["load.FN"] / lat.top.cols) * float(u[top_row, 1].sum())
        return total

    def block_geometry(self) -> np.ndarray:
        """[first array row, end array row, first array column, end array column, parity] of each block's
        nodes (``kernels.diagnostics``)."""
        out = []
        for b in (BOTTOM, TOP):
            B = self.layout.blocks[b]
            out.append([PAD, B.rows + PAD, B.j(B.span[0]), B.j(B.span[1]), B.parity])
        return np.array(out, np.int64)

    def stiffness(self) -> np.ndarray:
        m = self.setup.material
        return np.array([[m.kn_bottom, m.kt_bottom], [m.kn_top, m.kt_top]])

    def node_fields(self, n: int):
        """OWNED nodes at step n: positions (N, 3) in a, half-step velocities (u(n) - u(n-1))/dt (N, 3)
        in internal units, virial stress (N, 3) [sxx, syy, sxy] in rho c_r^2."""
        from .kernels.diagnostics import node_stress
        u = self.owned_u(n)
        v = (u - self.owned_u(n - 1)) / self.setup.dt
        pos = np.zeros((self.n_owned, 3))
        pos[:, 0] = self.ref_x + u[:, 0]
        pos[:, 1] = self.ref_y + u[:, 1]
        vel = np.zeros((self.n_owned, 3))
        vel[:, :2] = v
        sig = np.zeros((self.n_owned, 3))
        node_stress(*self.level(n), self.own_block, self.own_prow, self.own_j, self.block_geometry(),
                    self.stiffness(), DIRECTIONS, 0.5 / self.setup.material.c_r ** 2, sig)
        return pos, vel, sig
