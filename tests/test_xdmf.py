"""The snapshots as a time series in real viewers: ParaView's pvpython (Debian's 5.11) and pyvista.

Every number a viewer shows is compared with the datasets read directly
through h5py: time steps, points and cells per step, the bond connectivity,
the node fields and the bond flags.  pvpython runs as a subprocess, headless,
with a timeout; its tests are skipped only where pvpython is absent
(tests/install.sh installs Debian's paraview and python3-paraview).
"""
import json
import os
import shutil
import subprocess
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from parslip.cli import main
from parslip.io.xdmf import sidecar_path, write_xdmf

PVPYTHON = shutil.which("pvpython")
needs_pvpython = pytest.mark.skipif(PVPYTHON is None, reason="pvpython not found: ParaView's client is needed "
                                    "(tests/install.sh installs Debian's paraview and python3-paraview)")
PV_SCRIPT = os.path.join(os.path.dirname(__file__), "pv_read_xdmf.py")
POINT_FIELDS = ("velocity", "sxx", "syy", "sxy")
CELL_FIELDS = ("interface", "intact")
VTK_LINE, VTK_POLY_LINE = 3, 4


def expected(path):
    """Per snapshot, straight from the flat /VTKHDF datasets at the offsets /VTKHDF/Steps gives (either
    layout, io.mesh): times, points, bonds, fields.  Returns (times, points per step, cells per step, steps)."""
    with h5py.File(path, "r") as f:
        v = f["VTKHDF"]
        s = v["Steps"]
        t = s["Values"][...]
        steps = []
        for k in range(len(t)):
            part = int(s["PartOffsets"][k])
            N, M = int(v["NumberOfPoints"][part]), int(v["NumberOfCells"][part])
            p0, q0 = int(s["PointOffsets"][k]), int(s["ConnectivityIdOffsets"][k])
            steps.append({
                "points": v["Points"][p0:p0 + N],
                "bonds": v["Connectivity"][q0:q0 + 2 * M].reshape(M, 2),
                **{n: v[f"PointData/{n}"][int(s[f"PointDataOffsets/{n}"][k]):][:N] for n in POINT_FIELDS},
                **{n: v[f"CellData/{n}"][int(s[f"CellDataOffsets/{n}"][k]):][:M] for n in CELL_FIELDS},
            })
    return t, N, M, steps


def pvpython_read(path):
    """What ParaView shows of ``path`` opened as File > Open does (tests/pv_read_xdmf.py)."""
    # ParaView's own Python, not this one: none of this interpreter's paths.
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    p = subprocess.run([PVPYTHON, "--dr", "--no-mpi", "--force-offscreen-rendering", PV_SCRIPT, str(path)],
                       capture_output=True, text=True, timeout=300, env=env, cwd="/")
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


def assert_same_series(seen, path, cell_type):
    """A reader's time series equals the file's snapshots, step by step and value by value."""
    t, N, M, steps = expected(path)
    np.testing.assert_array_equal(seen["times"], t)
    assert len(seen["steps"]) == len(t) >= 2
    for k, (got, want) in enumerate(zip(seen["steps"], steps)):
        assert (got["n_points"], got["n_cells"]) == (N, M), f"step {k}"
        assert got["cell_types"] == [cell_type]
        np.testing.assert_array_equal(got["points"], want["points"], err_msg=f"points, step {k}")
        np.testing.assert_array_equal(got["offsets"], 2 * np.arange(M + 1))
        np.testing.assert_array_equal(np.reshape(got["connectivity"], (M, 2)), want["bonds"], err_msg=f"step {k}")
        for n in POINT_FIELDS:
            np.testing.assert_array_equal(got["point_data"][n], want[n], err_msg=f"{n}, step {k}")
        for n in CELL_FIELDS:
            np.testing.assert_array_equal(got["cell_data"][n], want[n], err_msg=f"{n}, step {k}")
    # The steps differ (else a reader stuck on one step would pass).
    assert not np.array_equal(steps[0]["points"], steps[-1]["points"])
    assert (steps[-1]["intact"] == 0).any() and steps[-1]["interface"].sum() < M


@pytest.fixture(scope="module")
def chunked_run(small_run, tmp_path_factory):
    """A copy of the small run with every /VTKHDF dataset chunked: the sidecar must not depend on layout."""
    out = tmp_path_factory.mktemp("chunked") / "chunked.vtkhdf"
    with h5py.File(small_run, "r") as src, h5py.File(out, "w") as dst:
        for k, val in src.attrs.items():
            dst.attrs[k] = val
        src.copy("interface", dst)

        def copy(name, obj):
            if isinstance(obj, h5py.Group):
                g = dst.require_group(name)
                for k, val in obj.attrs.items():
                    g.attrs[k] = val
            else:
                dst.create_dataset(name, data=obj[...], chunks=True, maxshape=(None,) + obj.shape[1:])
        dst.create_group("VTKHDF")
        src["VTKHDF"].visititems(lambda n, o: copy("VTKHDF/" + n, o))
        for k, val in src["VTKHDF"].attrs.items():
            dst["VTKHDF"].attrs[k] = val
    return str(out)


# ------------------------------------------------------------------ the sidecar --

def test_run_writes_sidecar_with_one_grid_per_snapshot(small_run):
    x = sidecar_path(small_run)
    assert x.endswith(".xdmf2") and os.path.exists(x)
    t, N, M, _ = expected(small_run)
    grids = ET.parse(x).getroot().find("Domain/Grid")
    assert grids.get("CollectionType") == "Temporal"
    steps = grids.findall("Grid")
    assert [float(g.find("Time").get("Value")) for g in steps] == list(t)
    assert {d.get("ItemType") for d in grids.iter("DataItem") if d.get("Format") != "XML"} == {"HyperSlab", None}
    assert all(int(g.find("Topology").get("NumberOfElements")) == M for g in steps)


def test_xdmf_subcommand_writes_sidecar(chunked_run, tmp_path):
    assert main(["xdmf", chunked_run]) == 0
    assert "chunked.vtkhdf:/VTKHDF/Points" in open(sidecar_path(chunked_run)).read()
    # Elsewhere: the data file is named relative to the sidecar.
    other = tmp_path / "views" / "c.xdmf"
    other.parent.mkdir()
    assert main(["xdmf", chunked_run, "-o", str(other)]) == 0
    assert os.path.relpath(chunked_run, other.parent) + ":/VTKHDF/Points" in other.read_text()


@pytest.mark.parametrize("bad", ["missing", "text", "h5"])
def test_xdmf_subcommand_bad_input(bad, tmp_path, capsys):
    path = tmp_path / "x.vtkhdf"
    if bad == "text":
        path.write_text("not a run")
    elif bad == "h5":
        with h5py.File(path, "w") as f:
            f["a"] = 1
    assert main(["xdmf", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("parslip: error: RUN") and err.count("\n") == 1


def test_xdmf_refuses_a_run_without_snapshots(small_run, tmp_path):
    from parslip.errors import ConfigError
    bare = tmp_path / "bare.vtkhdf"
    with h5py.File(small_run, "r") as src, h5py.File(bare, "w") as dst:
        src.copy("interface", dst)
    with pytest.raises(ConfigError, match="holds no snapshots"):
        write_xdmf(str(bare))


# --------------------------------------------------------------- ParaView 5.11 --

@needs_pvpython
@pytest.mark.parametrize("which", ["run", "chunked"])
def test_paraview_opens_sidecar_as_time_series(which, small_run, chunked_run):
    path = small_run if which == "run" else chunked_run
    write_xdmf(path)
    seen = pvpython_read(sidecar_path(path))
    assert seen["reader"] == "XdmfReader"        # .xdmf2 goes to "XDMF Reader" without a choice
    assert_same_series(seen, path, VTK_POLY_LINE)


@needs_pvpython
def test_paraview_version_is_one_the_readme_names():
    p = subprocess.run([PVPYTHON, "--version"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "paraview version 5." in (p.stdout + p.stderr).lower()


# ---------------------------------------------------------------------- pyvista --

def pyvista_series(reader):
    """(times, meshes) from a pyvista time-series reader."""
    out = []
    for t in reader.time_values:
        reader.set_active_time_value(t)
        out.append(reader.read())
    return list(reader.time_values), out


def as_seen(times, meshes):
    """pyvista meshes in the shape ``assert_same_series`` takes."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    steps = []
    for m in meshes:
        steps.append({"n_points": m.n_points, "n_cells": m.n_cells,
                      "cell_types": sorted(set(np.asarray(m.celltypes).tolist())),
                      "points": np.asarray(m.points), "offsets": vtk_to_numpy(m.GetCells().GetOffsetsArray()),
                      "connectivity": np.asarray(m.cell_connectivity),
                      "point_data": {n: np.asarray(m.point_data[n]) for n in POINT_FIELDS},
                      "cell_data": {n: np.asarray(m.cell_data[n]) for n in CELL_FIELDS}})
    return {"times": times, "steps": steps}


@pytest.mark.parametrize("which", ["run", "chunked"])
def test_pyvista_time_series_reader_on_sidecar(which, small_run, chunked_run):
    pv = pytest.importorskip("pyvista")
    path = small_run if which == "run" else chunked_run
    write_xdmf(path)
    r = pv.get_reader(sidecar_path(path), force_ext=".xdmf")
    assert type(r).__name__ == "XdmfReader"
    assert_same_series(as_seen(*pyvista_series(r)), path, VTK_POLY_LINE)


def test_pyvista_read_opens_first_snapshot_of_both_files(small_run):
    pv = pytest.importorskip("pyvista")
    _, N, M, steps = expected(small_run)
    for path, ext, cell_type in ((small_run, None, VTK_LINE), (sidecar_path(small_run), ".xdmf", VTK_POLY_LINE)):
        m = pv.read(path, force_ext=ext)
        seen = as_seen([0.0], [m])["steps"][0]
        assert (seen["n_points"], seen["n_cells"], seen["cell_types"]) == (N, M, [cell_type]), path
        np.testing.assert_array_equal(seen["points"], steps[0]["points"])
        np.testing.assert_array_equal(seen["point_data"]["sxy"], steps[0]["sxy"])
        # Bonds are 2-node lines; stresses are node fields, the bond flags cell fields.
        assert m.point_data["sxy"].shape == (N,) and m.cell_data["intact"].shape == (M,)


def test_pyvista_vtkhdf_steps_match_sidecar(small_run):
    """The .vtkhdf stepped through VTK's own VTKHDF reader equals the sidecar's series."""
    pv = pytest.importorskip("pyvista")
    r = pv.get_reader(small_run)
    r.reader.UpdateInformation()
    t, *_ = expected(small_run)
    assert r.reader.GetNumberOfSteps() == len(t)
    meshes = []
    for k in range(len(t)):
        r.reader.SetStep(k)
        meshes.append(r.read().copy())
    assert_same_series(as_seen(list(t), meshes), small_run, VTK_LINE)
