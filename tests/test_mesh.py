"""The snapshots' two layouts (``parslip.io.mesh``) read back alike, in every reader.

tests/data/snapshots_25429d0: a push run to 3 l/c_r written by the code at 25429d0, whose snapshots store
every step's bonds with the step (the per-step layout), with its last checkpoint.  Today's code continues
it to 6 l/c_r on 2 ranks (appending its later snapshots in the file's own layout) and runs the same scene
from the start, writing the shared mesh (the bonds stored once, a far end per interface site).  At every
time both files hold, every reader sees the same run: the project's contract reader and ``parslip.open``
by node id; pyvista (VTK's VTKHDF reader) and ParaView 5.11 (through the sidecar) as the same points and
the same bonds, segment for segment.
"""
import gzip
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

import parslip
from helpers import datasets, require, run_cli
from parslip.io.contract import read_snapshot_arrays
from parslip.io.xdmf import sidecar_path, write_xdmf
from test_xdmf import needs_pvpython, pvpython_read

DATA = Path(__file__).parent / "data" / "snapshots_25429d0"
SITES = 24
POINT_FIELDS = ("velocity", "sxx", "syy", "sxy")
CELL_FIELDS = ("interface", "intact")


def _continued(d: Path, writer: str) -> Path:
    out = d / f"old_{writer}.vtkhdf"
    for name, dest in (("run.vtkhdf.gz", out), ("run.vtkhdf.ckpt.h5.gz", Path(f"{out}.ckpt.h5"))):
        with gzip.open(DATA / name, "rb") as src, open(dest, "wb") as dst:
            shutil.copyfileobj(src, dst)
    p = run_cli(2, "run", DATA / "scene.toml", "--out", out, "--no-png", "--quiet", "--set", "drive.duration=6.0",
                "--restart", f"{out}.ckpt.h5", writer=writer)
    assert p.returncode == 0, p.stderr
    return out


@pytest.fixture(scope="module")
def layouts(tmp_path_factory):
    """(per-step file continued by today's code, shared-mesh file of today's code, the times both hold)."""
    require("gather")
    d = tmp_path_factory.mktemp("layouts")
    old = _continued(d, "gather")
    new = d / "new.vtkhdf"
    p = run_cli(1, "run", DATA / "scene.toml", "--out", new, "--no-png", "--quiet", "--set", "drive.duration=6.0")
    assert p.returncode == 0, p.stderr
    t_old, t_new = (parslip.open(str(f)).snapshot_times for f in (old, new))
    both = [(int(np.flatnonzero(t_old == t)[0]), k) for k, t in enumerate(t_new) if t in t_old]
    # 0 and 2 l/c_r written by the code at 25429d0, 4 and 6 appended by today's in the per-step layout.
    assert len(t_old) == 6 and len(both) == 4 and t_old[3] == pytest.approx(3.0, abs=0.01)
    return old, new, both


def test_the_two_files_have_the_two_layouts(layouts):
    old, new, _ = layouts
    with h5py.File(old, "r") as a, h5py.File(new, "r") as b:
        assert "snapshots" not in a and "snapshots" in b
        n = int(a.attrs["n_nodes"])
        S, M = len(a["VTKHDF/Steps/Values"]), int(a["VTKHDF/NumberOfCells"][0])
        assert list(a["VTKHDF/NumberOfPoints"][:S]) == [n] * S and a["VTKHDF/Connectivity"].shape[0] >= 2 * M * S
        assert list(b["VTKHDF/NumberOfPoints"]) == [n + SITES] and b["VTKHDF/Connectivity"].shape == (2 * M,)
        assert not b["VTKHDF/Steps/ConnectivityIdOffsets"][...].any() and not b["VTKHDF/Steps/PartOffsets"][...].any()


def test_the_contract_reads_the_same_snapshots_by_node_id(layouts):
    old, new, both = layouts
    for i, k in both:
        a, b = read_snapshot_arrays(str(old), i), read_snapshot_arrays(str(new), k)
        assert a.keys() == b.keys()
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"{name}, snapshot at {a['time']}")
    # Something happened: bonds broke, and some re-formed onto another substrate node.
    last = read_snapshot_arrays(str(new), both[-1][1])
    iface = last["interface"] == 1
    assert (last["intact"][iface] == 0).any()
    assert (last["cells"][iface, 1] - last["cells"][iface, 0] != last["cells"][iface][0, 1] - last["cells"][iface][0, 0]).any()


def test_parslip_open_gives_the_same_meshes(layouts):
    pytest.importorskip("pyvista")
    old, new, both = layouts
    a, b = parslip.open(str(old)), parslip.open(str(new))
    for i, k in both:
        ma, mb = a.snapshot(i), b.snapshot(k)
        np.testing.assert_array_equal(ma.points, mb.points)
        np.testing.assert_array_equal(ma.cell_connectivity, mb.cell_connectivity)
        np.testing.assert_array_equal(ma.celltypes, mb.celltypes)
        for name in POINT_FIELDS:
            np.testing.assert_array_equal(ma.point_data[name], mb.point_data[name])
        for name in CELL_FIELDS:
            np.testing.assert_array_equal(ma.cell_data[name], mb.cell_data[name])


def _same_picture(a: dict, b: dict, n: int, what: str):
    """Two readers' views of one snapshot (points, connectivity, fields) show the same lattice: the same
    first n points and their fields, every bond the same segment, the same cell fields."""
    pa, pb = np.asarray(a["points"]), np.asarray(b["points"])
    np.testing.assert_array_equal(pa[:n], pb[:n], err_msg=what)
    ends = lambda p, c: p[np.asarray(c).reshape(-1, 2)]       # noqa: E731
    np.testing.assert_array_equal(ends(pa, a["connectivity"]), ends(pb, b["connectivity"]), err_msg=what)
    for name in POINT_FIELDS:
        np.testing.assert_array_equal(np.asarray(a["point_data"][name])[:n], np.asarray(b["point_data"][name])[:n],
                                      err_msg=f"{what}: {name}")
    for name in CELL_FIELDS:
        np.testing.assert_array_equal(a["cell_data"][name], b["cell_data"][name], err_msg=f"{what}: {name}")


def _pyvista_step(path, k):
    import pyvista as pv
    r = pv.get_reader(str(path))
    r.reader.UpdateInformation()
    r.reader.SetStep(k)
    m = r.read()
    return {"points": m.points, "connectivity": m.cell_connectivity,
            "point_data": {n: m.point_data[n] for n in POINT_FIELDS},
            "cell_data": {n: m.cell_data[n] for n in CELL_FIELDS}}


def test_pyvista_shows_the_same_lattice(layouts):
    pytest.importorskip("pyvista")
    old, new, both = layouts
    n = parslip.open(str(new)).attrs["n_nodes"]
    for i, k in both:
        a, b = _pyvista_step(old, i), _pyvista_step(new, k)
        assert len(a["points"]) == n and len(b["points"]) == n + SITES
        _same_picture(a, b, n, f"pyvista, snapshots {i} and {k}")


@needs_pvpython
def test_paraview_5_11_shows_the_same_lattice(layouts):
    old, new, both = layouts
    n = parslip.open(str(new)).attrs["n_nodes"]
    seen = {}
    for f in (old, new):
        write_xdmf(str(f))
        seen[f] = pvpython_read(sidecar_path(str(f)))
        assert seen[f]["reader"] == "XdmfReader"
    for i, k in both:
        _same_picture(seen[old]["steps"][i], seen[new]["steps"][k], n, f"ParaView, snapshots {i} and {k}")


def test_the_shared_mesh_takes_about_half_the_bytes_of_a_snapshot(layouts):
    """Bytes a snapshot adds: every dataset of the per-step layout over its snapshot slots, against the
    shared layout's per-step datasets (the bonds, stored once, apart: less than one step of the other)."""
    old, new, _ = layouts
    once = ("Connectivity", "Offsets", "Types", "CellData/interface", "NumberOfPoints", "NumberOfCells",
            "NumberOfConnectivityIds")
    per, stored = {}, {}
    for f in (old, new):
        with h5py.File(f, "r") as h:
            slots = h["VTKHDF/Steps/PointOffsets"].shape[0]
            sizes = {}
            h.visititems(lambda name, o: sizes.__setitem__(name, o.size * o.dtype.itemsize)
                         if isinstance(o, h5py.Dataset) and name.startswith(("VTKHDF", "snapshots")) else None)
            stored[f] = sum(v for k, v in sizes.items() if k.split("/", 1)[1] in once) if f == new else 0
            per[f] = (sum(sizes.values()) - stored[f]) / slots
    assert per[new] < 0.6 * per[old] and stored[new] < per[old], (per, stored)


def test_the_collective_writer_continues_the_per_step_layout_alike(layouts, tmp_path):
    """The per-step layout appended through HDF5's collective mpio driver: the same datasets, byte for byte."""
    require("mpio")
    old, _, _ = layouts
    got, _ = datasets(_continued(tmp_path, "mpio"))
    want, _ = datasets(old)
    assert got.keys() == want.keys()
    for name in want:
        assert got[name].tobytes() == want[name].tobytes(), name
