"""parslip.open: the read-only result object over a real run file, checked against h5py and pyvista directly."""
import subprocess
import sys

import h5py
import numpy as np
import pytest

import parslip
from parslip.errors import ConfigError


def test_import_parslip_stays_cheap():
    code = "import sys, parslip; print('numpy' in sys.modules, 'h5py' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_interface_scene_and_attrs_match_the_file(small_run):
    run = parslip.open(small_run)
    with h5py.File(small_run, "r") as f:
        n = int(f["interface"].attrs["frames_written"])
        np.testing.assert_array_equal(run.interface["intact"], f["interface/intact"][:n])
        np.testing.assert_array_equal(run.times, f["interface/time"][:n])
        np.testing.assert_array_equal(run.x, f["interface/x"][...])
        assert run.attrs["c_r"] == f.attrs["c_r"]
    assert run.scene["drive.mode"] == "push" and run.scene["lattice.top_cols"] == 24
    assert run.scene["drive.duration"] == 10.0 and run.v0 == 0.02
    assert run.units["ux"] == "l" and run.units["t"] == "l/c_r"
    assert run.attrs["status"] == "complete" and "git_commit" in run.attrs
    # frame cadence is one a/c_r by default: 1/top_cols in l/c_r
    assert np.diff(run.times) == pytest.approx(np.full(len(run.times) - 1, 1 / 24), rel=0.05)


def test_snapshots_are_pyvista_meshes_at_their_times(small_run):
    pv = pytest.importorskip("pyvista")
    run = parslip.open(small_run)
    assert len(run.snapshot_times) == 5 and run.snapshot_times[0] == 0.0
    assert run.snapshot_times[-1] == pytest.approx(10.0, abs=0.1)
    r = pv.get_reader(small_run, force_ext=".vtkhdf")
    r.reader.UpdateInformation()
    n = run.attrs["n_nodes"]
    for k in (0, 2, -1):
        mesh = run.snapshot(k)
        r.reader.SetStep(k % 5)
        direct = r.read()
        # The run's mesh is the nodes alone; the file's snapshot also has one far end per interface site
        # (io.mesh), where the bond's other node stands: every bond is the same segment in both.
        assert mesh.n_points == n and direct.n_points == n + 24 and mesh.n_cells == direct.n_cells
        np.testing.assert_array_equal(mesh.points, direct.points[:n])
        np.testing.assert_array_equal(mesh.point_data["sxy"], direct.point_data["sxy"][:n])
        ends = lambda m: np.asarray(m.points)[np.asarray(m.cell_connectivity).reshape(-1, 2)]   # noqa: E731
        np.testing.assert_array_equal(ends(mesh), ends(direct))
        np.testing.assert_array_equal(mesh.cell_data["intact"], direct.cell_data["intact"])
        assert r.reader.GetTimeValue() == pytest.approx(run.snapshot_times[k]) == mesh.field_data["Time"][0]
    near = run.snapshot_at(run.snapshot_times[2] + 0.3)
    np.testing.assert_array_equal(near.point_data["sxx"], run.snapshot(2).point_data["sxx"])
    assert set(near.cell_data) >= {"interface", "intact"}


def test_fronts_are_those_of_the_interface_record(small_run):
    from parslip.analysis.fronts import fronts
    from parslip.analysis.results import Run
    run = parslip.open(small_run)
    drawn = Run.from_arrays(run.interface, run.scene, run.attrs)       # the same arrays, held in memory
    assert [f.nucleation_time for f in run.fronts()] == [f.nucleation_time for f in fronts(drawn)]
    assert run.fronts() and run.fronts()[0].direction == 1


@pytest.mark.parametrize("make,message", [
    (lambda d: str(d / "nope.vtkhdf"), "no such file"),
    (lambda d: str(d), "is a directory"),
    (lambda d: (d / "t.txt").write_text("x") and str(d / "t.txt"), "not an HDF5 file"),
    (lambda d: h5py.File(d / "o.h5", "w").close() or str(d / "o.h5"), "without /interface"),
])
def test_bad_paths_give_one_line(tmp_path, make, message):
    path = make(tmp_path)
    with pytest.raises(ConfigError, match=message) as e:
        parslip.open(path)
    assert "\n" not in str(e.value) and repr(path) in str(e.value)


def test_snapshot_out_of_range_names_the_range(small_run):
    with pytest.raises(ConfigError, match="-5 <= k < 5"):
        parslip.open(small_run).snapshot(7)
