"""The XDMF sidecar of a run file: the snapshots as a time series for any ParaView.

Responsible for ``<run>.xdmf2``, an XML file next to the run file that points
into its ``/VTKHDF`` datasets, one grid per snapshot.  ParaView from 5.11 on
(Debian 12's package, whose VTKHDF reader knows format 1.0 only and shows
every snapshot stacked as one mesh) opens it as a time series with its
"XDMF Reader"; so do VTK's ``vtkXdmfReader`` and pyvista.  Newer ParaView
also opens the ``.vtkhdf`` itself.  The sidecar holds no data and
can be rewritten at any time (``parslip xdmf RUN``).

What it describes, per snapshot k, from the offsets in /VTKHDF/Steps (so it
serves both layouts of ``io.mesh``: the shared mesh, and the per-step cells
of files written before), one Uniform grid per step:

  Time        /VTKHDF/Steps/Values[k], in l/c_r
  Geometry    the step's P points of /VTKHDF/Points from PointOffsets[k]
              (x, y, z in a; P = N nodes, plus one far end per interface site
              in the shared layout)
  Topology    Polyline, 2 nodes per element: M cells of /VTKHDF/Connectivity
              from ConnectivityIdOffsets[k] (the same entries for every step
              of the shared layout, which stores its bonds once).  Ids run
              0..P-1 within the step, which is what a grid whose geometry is
              the step's rows needs, so no shift is applied.  A broken
              interface bond is a zero-length line.
  Node fields velocity (3 components, internal velocity unit), sxx, syy, sxy
              (rho c_r^2), from PointDataOffsets[k]
  Cell fields interface (1 for an interface bond), intact (1 if intact), from
              CellDataOffsets[k]

The shared layout's interface cells cannot be told apart from the bulk by a
viewer otherwise than through ``interface``; one grid per step (rather than a
spatial collection of the bulk and the interface) keeps what ParaView 5.11
shows identical to what VTK's own VTKHDF reader shows of the run file.

Each slice is an XDMF ``HyperSlab`` (start, stride, count per axis) of the
HDF5 dataset named by path, so it holds whatever the storage layout.

Why ``.xdmf2``: ParaView offers three readers for ``.xmf``/``.xdmf`` (a dialog
in the GUI; ``OpenDataFile`` takes Xdmf3ReaderS) but only "XDMF Reader" (the
Xdmf2 library) for ``.xmf2``/``.xdmf2``, and only that one reads these files:
the Xdmf3 readers of 5.11 return no points for a floating-point HyperSlab.
Byte-addressed ``Binary``/``Seek`` items, which the Xdmf3 readers do take,
were measured wrong in "XDMF Reader" (it caches topology and geometry by
data-file name, so every step showed the first step's mesh) and limited to
2 GiB (``Seek`` is parsed with ``atoi``).  pyvista reads the sidecar with
``pv.get_reader(path, force_ext=".xdmf")``; it reads the ``.vtkhdf`` itself too.

Rewrite the sidecar (``parslip xdmf RUN``) after renaming the run file.
"""
from __future__ import annotations

import os
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..errors import ConfigError
from .contract import VTKHDF, check_run_file

SUFFIX = ".xdmf2"           # the extension ParaView gives to "XDMF Reader" alone (see above)

# name in the file -> XDMF AttributeType; sizes and number types come from the datasets.
POINT_FIELDS = {"velocity": "Vector", "sxx": "Scalar", "syy": "Scalar", "sxy": "Scalar"}
CELL_FIELDS = {"interface": "Scalar", "intact": "Scalar"}

# numpy kind and item size -> XDMF NumberType
_NUMBER_TYPE = {("f", 8): "Float", ("f", 4): "Float", ("i", 8): "Int", ("i", 4): "Int",
                ("u", 1): "UChar", ("u", 4): "UInt", ("i", 1): "Char"}


def sidecar_path(run_path: str) -> str:
    """``out/push.vtkhdf`` -> ``out/push.xdmf2``."""
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
    steps = v["Steps"]
    times = np.asarray(steps["Values"][...], dtype=float)
    lines = ['<?xml version="1.0" ?>',
             '<!-- parslip snapshots: positions in a, stress in rho c_r^2, times in l/c_r; '
             f'HyperSlabs of {escape(ref)}; rewrite with `parslip xdmf RUN` -->',
             '<Xdmf Version="2.0">', "<Domain>",
             '<Grid Name="snapshots" GridType="Collection" CollectionType="Temporal">']
    at = {name: np.asarray(steps[name][:len(times)], np.int64) for name in
          ("PartOffsets", "PointOffsets", "ConnectivityIdOffsets")}
    fields = {(group, name): np.asarray(steps[f"{group}Offsets/{name}"][:len(times)], np.int64)
              for group, names in (("PointData", POINT_FIELDS), ("CellData", CELL_FIELDS)) for name in names}
    for k in range(len(times)):
        part = int(at["PartOffsets"][k])
        N, M = int(v["NumberOfPoints"][part]), int(v["NumberOfCells"][part])
        lines.append(f'<Grid Name="snapshot {k}" GridType="Uniform">')
        lines.append(f'<Time TimeType="Single" Value="{float(times[k])!r}"/>')
        lines.append(f'<Topology TopologyType="Polyline" NodesPerElement="2" NumberOfElements="{M}">')
        lines.append(_hyperslab(v, ref, "Connectivity", int(at["ConnectivityIdOffsets"][k]), 2 * M, shape=(M, 2)))
        lines.append("</Topology>")
        lines.append('<Geometry GeometryType="XYZ">')
        lines.append(_hyperslab(v, ref, "Points", int(at["PointOffsets"][k]), N))
        lines.append("</Geometry>")
        for (group, name), first in fields.items():
            kind = (POINT_FIELDS if group == "PointData" else CELL_FIELDS)[name]
            center = "Node" if group == "PointData" else "Cell"
            lines.append(f'<Attribute Name={quoteattr(name)} AttributeType="{kind}" Center="{center}">')
            lines.append(_hyperslab(v, ref, f"{group}/{name}", int(first[k]), N if group == "PointData" else M))
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


def _dims(ds, rows: int, shape) -> str:
    return " ".join(map(str, shape or ((rows,) + ds.shape[1:])))


def _hyperslab(v, ref, name, first, rows, shape=None) -> str:
    """Rows ``first .. first+rows-1`` of ``/VTKHDF/name`` as an XDMF HyperSlab: a 3 x rank XML
    array (start, stride, count per axis) and the whole HDF5 dataset it selects from; ``shape``
    overrides the result's dimensions (the flat connectivity read as M x 2)."""
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
