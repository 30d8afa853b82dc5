"""The XDMF sidecar of a run file: the snapshots as a time series for any ParaView.

Responsible for ``<run>.xdmf``, an XML file next to the run file that points
into its ``/VTKHDF`` datasets, one grid per snapshot.  ParaView from 5.11 on
(Debian 12's package, whose VTKHDF reader knows format 1.0 only and shows
every snapshot stacked as one mesh) opens it as a time series; so do VTK's
``vtkXdmfReader`` and pyvista (``pv.read``, ``pv.get_reader``).  Newer
ParaView also opens the ``.vtkhdf`` itself.  The sidecar holds no data and
can be rewritten at any time (``parslip xdmf RUN``).

What it describes, per snapshot k of S (N points, M cells per snapshot; the
flat datasets hold the snapshots one after the other):

  Time        /VTKHDF/Steps/Values[k], in l/c_r
  Geometry    /VTKHDF/Points rows k*N .. k*N+N-1 (x, y, z in a)
  Topology    Polyline, 2 nodes per element: /VTKHDF/Connectivity entries
              2kM .. 2kM+2M-1.  Connectivity holds node ids 0..N-1 within the
              snapshot (VTKHDF adds PointOffsets), which is exactly what a grid
              whose geometry is rows k*N.. needs, so no shift is applied.  A
              broken interface bond is a zero-length line (both ends the top node).
  Node fields velocity (3 components, internal velocity unit), sxx, syy, sxy
              (rho c_r^2), rows k*N ..
  Cell fields interface (1 for an interface bond), intact (1 if intact), rows k*M ..

Two ways to point at a slice, chosen per file:

* ``Binary`` with ``Seek``: the byte address of the slice inside the HDF5 file
  (contiguous storage address + first row x row size).  ParaView 5.11's three
  XDMF readers (XDMF Reader, Xdmf3ReaderS, Xdmf3ReaderT) all read it, so any
  reader a user picks in ParaView's dialog shows the data.  Usable only when
  every dataset is stored contiguous, unfiltered and little-endian (what
  ``io.output`` writes) and every address is below 2**31 (both XDMF libraries
  parse ``Seek`` with ``atoi``), i.e. files up to about 2 GiB.
* ``HyperSlab`` (start, stride, count) into the HDF5 dataset by name: the XDMF
  standard, independent of storage layout and size.  ParaView 5.11 reads it
  with "XDMF Reader" only: its Xdmf3 readers return no points for a
  floating-point hyperslab.  Used when the Binary rule above does not hold.

A rewritten or repacked run file moves the addresses: rewrite the sidecar
(``parslip xdmf RUN``) after anything but ``parslip run`` has written the file.
"""
from __future__ import annotations

import os
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..errors import ConfigError
from .contract import VTKHDF, check_run_file

SUFFIX = ".xdmf"
ATOI_MAX = 2**31 - 1        # largest Seek both XDMF libraries parse (atoi into int)

# name in the file -> (XDMF AttributeType, Center); sizes and types come from the datasets.
POINT_FIELDS = {"velocity": "Vector", "sxx": "Scalar", "syy": "Scalar", "sxy": "Scalar"}
CELL_FIELDS = {"interface": "Scalar", "intact": "Scalar"}

# numpy kind and item size -> XDMF NumberType
_NUMBER_TYPE = {("f", 8): "Float", ("f", 4): "Float", ("i", 8): "Int", ("i", 4): "Int",
                ("u", 1): "UChar", ("u", 4): "UInt", ("i", 1): "Char"}


def sidecar_path(run_path: str) -> str:
    """``out/push.vtkhdf`` -> ``out/push.xdmf``."""
    return os.path.splitext(run_path)[0] + SUFFIX


def write_xdmf(run_path: str, out: str | None = None) -> str:
    """Write the XDMF sidecar of ``run_path`` (default ``sidecar_path(run_path)``); return its path.

    Raises ``ConfigError`` (one line) if ``run_path`` is not a run file or holds
    no snapshots.  Describes the snapshots written so far (``Steps/Values``),
    so it also serves a failed or interrupted run.
    """
    import h5py

    check_run_file(run_path)
    out = out or sidecar_path(run_path)
    with h5py.File(run_path, "r") as f:
        if VTKHDF not in f or "Steps" not in f[VTKHDF]:
            raise ConfigError(f"RUN {run_path!r}: holds no snapshots; accepted: a run with output.snapshots > 0")
        xml = _document(f[VTKHDF], _heavy_ref(run_path, out))
    tmp = out + ".tmp"
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(xml)
    os.replace(tmp, out)            # a reader never sees half a file
    return out


def _heavy_ref(run_path: str, xdmf_path: str) -> str:
    """The run file as the sidecar names it: relative to the sidecar's folder, so the pair can move."""
    return os.path.relpath(os.path.abspath(run_path), os.path.dirname(os.path.abspath(xdmf_path)))


def _document(v, ref: str) -> str:
    times = np.asarray(v["Steps"]["Values"][...], dtype=float)
    S = len(times)
    N, M = int(v["NumberOfPoints"][0]), int(v["NumberOfCells"][0])
    names = ["Points", "Connectivity"] + [f"PointData/{n}" for n in POINT_FIELDS] + \
            [f"CellData/{n}" for n in CELL_FIELDS]
    binary = all(_binary_ok(v[n]) for n in names)
    item = _binary_item if binary else _hyperslab_item
    lines = ['<?xml version="1.0" ?>',
             '<!-- parslip snapshots: positions in a, stress in rho c_r^2, times in l/c_r; '
             f'{"Binary/Seek into" if binary else "HyperSlabs of"} {escape(ref)} -->',
             '<Xdmf Version="2.0">', "<Domain>",
             '<Grid Name="snapshots" GridType="Collection" CollectionType="Temporal">']
    for k in range(S):
        lines.append(f'<Grid Name="snapshot {k}" GridType="Uniform">')
        lines.append(f'<Time TimeType="Single" Value="{float(times[k])!r}"/>')
        lines.append(f'<Topology TopologyType="Polyline" NodesPerElement="2" NumberOfElements="{M}">')
        lines.append(item(v, ref, "Connectivity", 2 * k * M, 2 * M, shape=(M, 2)))
        lines.append("</Topology>")
        lines.append('<Geometry GeometryType="XYZ">')
        lines.append(item(v, ref, "Points", k * N, N))
        lines.append("</Geometry>")
        for group, fields, rows, first in (("PointData", POINT_FIELDS, N, k * N), ("CellData", CELL_FIELDS, M, k * M)):
            center = "Node" if group == "PointData" else "Cell"
            for name, kind in fields.items():
                lines.append(f'<Attribute Name={quoteattr(name)} AttributeType="{kind}" Center="{center}">')
                lines.append(item(v, ref, f"{group}/{name}", first, rows))
                lines.append("</Attribute>")
        lines.append("</Grid>")
    lines += ["</Grid>", "</Domain>", "</Xdmf>", ""]
    return "\n".join(lines)


def _type_attrs(ds) -> str:
    dt = ds.dtype
    try:
        number = _NUMBER_TYPE[(dt.kind, dt.itemsize)]
    except KeyError:
        raise ConfigError(f"dataset {ds.name}: type {dt} has no XDMF number type; "
                          f"accepted: {sorted(set(_NUMBER_TYPE.values()))}") from None
    return f'NumberType="{number}" Precision="{dt.itemsize}"'


def _binary_ok(ds) -> bool:
    """Raw bytes of ``ds`` are addressable: contiguous, unfiltered, little-endian, allocated, below 2**31."""
    addr = ds.id.get_offset()
    order = ds.dtype.byteorder
    little = order in "<|" or (order == "=" and np.little_endian)
    return (ds.chunks is None and not ds.compression and little and addr is not None
            and addr + ds.id.get_storage_size() <= ATOI_MAX)


def _dims(ds, rows: int, shape) -> str:
    return " ".join(map(str, shape or ((rows,) + ds.shape[1:])))


def _binary_item(v, ref, name, first, rows, shape=None) -> str:
    """Rows ``first .. first+rows-1`` of ``/VTKHDF/name`` by byte address (Seek) in the run file."""
    ds = v[name]
    row_bytes = ds.dtype.itemsize * int(np.prod(ds.shape[1:], dtype=np.int64))
    seek = ds.id.get_offset() + first * row_bytes
    return (f'<DataItem Format="Binary" Endian="Little" Seek="{seek}" Dimensions="{_dims(ds, rows, shape)}" '
            f'{_type_attrs(ds)}>{escape(ref)}</DataItem>')


def _hyperslab_item(v, ref, name, first, rows, shape=None) -> str:
    """Rows ``first .. first+rows-1`` of ``/VTKHDF/name`` as an XDMF HyperSlab (start, stride, count per axis)."""
    ds = v[name]
    rank = ds.ndim
    start = [first] + [0] * (rank - 1)
    count = [rows] + list(ds.shape[1:])
    sel = " ".join(map(str, start + [1] * rank + count))
    full = " ".join(map(str, ds.shape))
    t = _type_attrs(ds)
    return (f'<DataItem ItemType="HyperSlab" Type="HyperSlab" Dimensions="{_dims(ds, rows, shape)}" {t}>'
            f'<DataItem Dimensions="3 {rank}" Format="XML">{sel}</DataItem>'
            f'<DataItem Dimensions="{full}" {t} Format="HDF">{escape(ref)}:{ds.name}</DataItem>'
            "</DataItem>")
