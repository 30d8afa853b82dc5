"""Where the snapshots go in /VTKHDF: the two layouts of the transient UnstructuredGrid, as pieces per rank.

A snapshot is the whole lattice: N nodes (points, in global id order) and M = nb + ns line cells (the
nb bulk bonds in global order, then one cell per interface site, in site order).  The bulk bonds never
change; an interface cell joins a site's top node to the node at its far end, which changes as the bond
breaks and re-forms.  VTK's reader takes a step's parts from consecutive rows of every dataset (one
part's points, cells and connectivity right after the previous part's, from the step's offsets in
``Steps``), so a shared bulk connectivity can only serve every step if the interface cells' connectivity
is constant too.  Hence the layouts:

shared (written now, ``SHARED``)
    The connectivity, cell offsets, cell types and the ``interface`` flag are stored once, and every
    step's ``Steps`` offsets point at them (offset 0, repeated; one part, ``PartOffsets`` 0).  Each step
    has P = N + ns points: the N nodes, then one point per interface site standing at the far end of its
    interface cell (its bond's substrate node, or its own top node while broken or bonded to a rigid
    substrate) and carrying its top node's velocity and stresses; interface cell s joins top node s to
    point N + s, so its connectivity never changes.  Per step: the P points and point fields, the M
    ``intact`` flags, and in ``/snapshots/far_node`` the global id of each far end (what the project's
    readers turn back into the cells of the node ids, ``io.contract.read_snapshot_arrays``).  About half
    the bytes of a step of the per-step layout.
per-step (files written before, ``PER_STEP``; a restart of such a run goes on in it)
    Every step its own N points, M cells and 2 M connectivity ids, the interface cells joining node ids.

Every rank writes its own nodes (a contiguous range of global ids), its own bulk cells (those of its
columns: contiguous, the same whatever the rank count) and its own sites' cells, so the file does not
depend on the rank count.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .contract import FAR_NODE, SNAPSHOTS, VTKHDF

SHARED, PER_STEP = "shared", "per-step"
VTK_LINE = 3
POINT_FIELDS = ("velocity", "sxx", "syy", "sxy")
CELL_FIELDS = ("interface", "intact")


@dataclass(frozen=True)
class Mesh:
    """The sizes of a snapshot: ``nodes`` N, ``sites`` ns, ``bulk`` nb bulk cells; ``layout`` SHARED or
    PER_STEP."""
    nodes: int
    sites: int
    bulk: int
    layout: str = SHARED

    @property
    def shared(self) -> bool:
        return self.layout == SHARED

    @property
    def cells(self) -> int:
        """M = nb + ns line cells."""
        return self.bulk + self.sites

    @property
    def points(self) -> int:
        """P, the points of one step: N, and one far end per interface site in the shared layout."""
        return self.nodes + (self.sites if self.shared else 0)

    def shapes(self, S: int) -> dict:
        """Shape of every dataset for S snapshots, by path (``VTKHDF/...``, ``snapshots/far_node``)."""
        P, M = self.points, self.cells
        parts = 1 if self.shared else S             # the shared layout's single part, or a part per step
        shapes = {"NumberOfPoints": (parts,), "NumberOfCells": (parts,), "NumberOfConnectivityIds": (parts,),
                  "Points": (S * P, 3), "Types": (parts * M,), "Offsets": (parts * (M + 1),),
                  "Connectivity": (parts * 2 * M,), "PointData/velocity": (S * P, 3),
                  "CellData/interface": (parts * M,), "CellData/intact": (S * M,),
                  "Steps/Values": (S,), "Steps/PartOffsets": (S,), "Steps/NumberOfParts": (S,),
                  "Steps/PointOffsets": (S,), "Steps/CellOffsets": (S,), "Steps/ConnectivityIdOffsets": (S,)}
        for name in POINT_FIELDS[1:]:
            shapes[f"PointData/{name}"] = (S * P,)
        for name in POINT_FIELDS:
            shapes[f"Steps/PointDataOffsets/{name}"] = (S,)
        for name in CELL_FIELDS:
            shapes[f"Steps/CellDataOffsets/{name}"] = (S,)
        out = {f"{VTKHDF}/{name}": shape for name, shape in shapes.items()}
        if self.shared:
            out[f"{SNAPSHOTS}/{FAR_NODE}"] = (S * self.sites,)
        return out

    def grows(self, path: str) -> bool:
        """Whether dataset ``path`` has rows for every snapshot (resized when a restart adds some)."""
        return self.shapes(2)[path][0] != self.shapes(1)[path][0]

    def rows_per_chunk(self, path: str) -> int:
        """Rows of one snapshot (or of the stored mesh) in dataset ``path``: its natural chunk."""
        P, M = self.points, self.cells
        name = path.split("/", 1)[1]
        if name.startswith(("Points", "PointData")):
            return P
        return {"Connectivity": 2 * M, "Offsets": M + 1, "Types": M, "CellData/interface": M,
                "CellData/intact": M, FAR_NODE: max(self.sites, 1)}.get(name, 64)

    @staticmethod
    def dtype(path: str):
        """The number type of dataset ``path``."""
        name = path.split("/", 1)[1]
        if name in ("Types", "CellData/interface", "CellData/intact"):
            return np.uint8
        return np.float64 if name.startswith(("Points", "PointData")) or name == "Steps/Values" else np.int64

    def step_values(self, k: np.ndarray) -> dict:
        """The ``Steps`` offsets and part counts of snapshots ``k`` (written when the file is made or grows), by
        path."""
        P, M = self.points, self.cells
        zero = np.zeros(len(k), np.int64)
        out = {"Steps/PartOffsets": zero if self.shared else k, "Steps/NumberOfParts": np.ones(len(k), np.int64),
               "Steps/PointOffsets": k * P, "Steps/CellOffsets": zero if self.shared else k * M,
               "Steps/ConnectivityIdOffsets": zero if self.shared else k * 2 * M,
               "Steps/CellDataOffsets/interface": zero if self.shared else k * M,
               "Steps/CellDataOffsets/intact": k * M}
        for name in POINT_FIELDS:
            out[f"Steps/PointDataOffsets/{name}"] = k * P
        out = {f"{VTKHDF}/{name}": v for name, v in out.items()}
        if not self.shared:
            for name, v in self.counts().items():
                out[name] = np.full(len(k), v[0], np.int64)
        return out

    def counts(self) -> dict:
        """NumberOfPoints, NumberOfCells, NumberOfConnectivityIds of one part, by path."""
        return {f"{VTKHDF}/NumberOfPoints": np.array([self.points], np.int64),
                f"{VTKHDF}/NumberOfCells": np.array([self.cells], np.int64),
                f"{VTKHDF}/NumberOfConnectivityIds": np.array([2 * self.cells], np.int64)}


@dataclass(frozen=True)
class Share:
    """One rank's share of a snapshot: nodes node0 .. node0 + n_nodes - 1 (global ids), bulk cells cell0 ..
    cell0 + n_bulk - 1, interface sites site0 .. site0 + len(top_gid) - 1 (``top_gid``: their top nodes'
    global ids); ``last``: this rank writes the final entry of the cell offsets."""
    node0: int
    n_nodes: int
    cell0: int
    n_bulk: int
    site0: int
    top_gid: np.ndarray
    last: bool


def _rows(a: int, n: int):
    return (slice(a, a + n),)


def static_pieces(mesh: Mesh, me: Share, bulk_cells: np.ndarray) -> list:
    """The shared layout's stored mesh, this rank's part: [(dataset, rows, values)], the same datasets in
    the same order on every rank (rows None: none here).  ``bulk_cells`` [n_bulk, 2]: its bulk bonds."""
    nb, ns, N, M = mesh.bulk, len(me.top_gid), mesh.nodes, mesh.cells
    i0 = nb + me.site0                                      # this rank's first interface cell
    iface = np.stack([me.top_gid, N + me.site0 + np.arange(ns)], axis=1).ravel()
    cells = np.arange(me.cell0, me.cell0 + me.n_bulk, dtype=np.int64)
    sites = np.arange(i0, i0 + ns, dtype=np.int64)
    return [("VTKHDF/Connectivity", _rows(2 * me.cell0, 2 * me.n_bulk), bulk_cells.ravel()),
            ("VTKHDF/Connectivity", _rows(2 * i0, 2 * ns), iface),
            ("VTKHDF/Offsets", _rows(me.cell0, me.n_bulk), 2 * cells),
            ("VTKHDF/Offsets", _rows(i0, ns), 2 * sites),
            ("VTKHDF/Offsets", _rows(M, 1) if me.last else None, np.array([2 * M], np.int64)),
            ("VTKHDF/Types", _rows(me.cell0, me.n_bulk), np.full(me.n_bulk, VTK_LINE, np.uint8)),
            ("VTKHDF/Types", _rows(i0, ns), np.full(ns, VTK_LINE, np.uint8)),
            ("VTKHDF/CellData/interface", _rows(me.cell0, me.n_bulk), np.zeros(me.n_bulk, np.uint8)),
            ("VTKHDF/CellData/interface", _rows(i0, ns), np.ones(ns, np.uint8))]


def snapshot_pieces(mesh: Mesh, me: Share, k: int, fields: dict, far_gid: np.ndarray, far_pos: np.ndarray,
                    intact: np.ndarray, bulk_cells: np.ndarray | None) -> list:
    """Snapshot ``k``, this rank's part: [(dataset, rows, values)] as ``static_pieces``.  ``fields``: the
    OWNED nodes' ``points`` (n, 3), ``velocity`` (n, 3) and ``sxx``, ``syy``, ``sxy`` (n,); ``far_gid``,
    ``far_pos`` (ns, 3): each site's far end; ``intact`` (ns,) uint8; ``bulk_cells``: this rank's bulk
    bonds (the per-step layout writes them with every step)."""
    P, M, N, nb = mesh.points, mesh.cells, mesh.nodes, mesh.bulk
    ns = len(me.top_gid)
    top = me.top_gid - me.node0                             # the sites' top nodes among the OWNED nodes
    nodes = _rows(k * P + me.node0, me.n_nodes)
    i0 = k * M + nb + me.site0                              # this rank's first interface cell of step k
    out = []
    for name in ("Points",) + tuple(f"PointData/{n}" for n in POINT_FIELDS):
        values = fields["points" if name == "Points" else name.split("/")[1]]
        out.append((f"VTKHDF/{name}", nodes, values))
        if mesh.shared:                                     # the far ends: where they stand, their top's fields
            out.append((f"VTKHDF/{name}", _rows(k * P + N + me.site0, ns), far_pos if name == "Points" else
                        values[top]))
    ones = np.ones(me.n_bulk, np.uint8)
    out += [("VTKHDF/CellData/intact", _rows(k * M + me.cell0, me.n_bulk), ones),
            ("VTKHDF/CellData/intact", _rows(i0, ns), intact)]
    if mesh.shared:
        out.append((f"{SNAPSHOTS}/{FAR_NODE}", _rows(k * mesh.sites + me.site0, ns), far_gid))
        return out
    pairs = np.stack([me.top_gid, far_gid], axis=1).ravel()
    return out + [("VTKHDF/Connectivity", _rows(2 * (k * M + me.cell0), 2 * me.n_bulk), bulk_cells.ravel()),
                  ("VTKHDF/Connectivity", _rows(2 * i0, 2 * ns), pairs),
                  ("VTKHDF/CellData/interface", _rows(k * M + me.cell0, me.n_bulk), np.zeros(me.n_bulk, np.uint8)),
                  ("VTKHDF/CellData/interface", _rows(i0, ns), np.ones(ns, np.uint8))]


def per_step_cells(mesh: Mesh, j: int) -> list:
    """The per-step layout's cell offsets and types of step ``j`` (rank 0 writes them when the file is made or
    grows, one step at a time)."""
    M = mesh.cells
    return [("VTKHDF/Offsets", _rows(j * (M + 1), M + 1), 2 * np.arange(M + 1, dtype=np.int64)),
            ("VTKHDF/Types", _rows(j * M, M), np.full(M, VTK_LINE, np.uint8))]
