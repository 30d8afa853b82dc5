"""The output contract: interface datasets, VTKHDF snapshots that pyvista opens, provenance."""
import os

import h5py
import numpy as np
import pytest

from helpers import small_toml
from parslip import analysis
from parslip.analysis.results import Run
from parslip.cli import main
from parslip.io.contract import read_status

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")



@pytest.fixture(scope="module")
def result(tmp_path_factory):
    d = tmp_path_factory.mktemp("out")
    sc = d / "small.toml"
    sc.write_text(small_toml(**{"drive.mode": "pull", "drive.duration": 4.0, "output.snapshots": 2}))
    out = d / "small.vtkhdf"
    assert main(["run", str(sc), "--out", str(out), "--quiet"]) == 0
    return out


def test_interface_contract(result):
    with h5py.File(result, "r") as f:
        g = f["interface"]
        nf, ns = g["intact"].shape
        assert ns == 24 and g["intact"].dtype == np.uint8
        assert g["ux"].shape == g["uy"].shape == (nf, ns) and g["time"].shape == (nf,)
        x, t = g["x"][...], g["time"][...]
        assert np.all(np.diff(x) > 0) and 0 <= x[0] < 0.03 and 0.97 < x[-1] <= 1
        # One frame per lattice spacing crossed by a front at c_r: dt_frame <= (a/c_r) = 1/l in l/c_r.
        assert t[0] == 0.0 and np.diff(t).max() <= 1.0 / 24 + 1e-12
        assert t[-1] == pytest.approx(4.0, abs=1.0 / 24)
        assert g.attrs["frames_written"] == nf
        a = f.attrs
        for key in ("scene", "parslip_version", "git_commit", "dt", "omega_max", "c_s", "c_l", "c_r",
                    "n_nodes", "n_steps", "n_ranks"):
            assert key in a, key
        assert read_status(f) == "complete" and a["n_nodes"] == 4 * 24 + 4 * 40
        assert 'mode = "pull"' in a["scene"] and "v0 = 0.02" in a["scene"]
        assert a["dt"] < 2 / a["omega_max"]
        assert (g["intact"][...] == 0).any()                 # something happened
        # Pull: the driven front face moves at v0 c_r: ux of the front node at the end ~ v0 t (in l).
        assert g["ux"][-1, -1] == pytest.approx(0.02 * t[-1], rel=0.5)


def test_vtkhdf_opens_in_pyvista(result):
    pv = pytest.importorskip("pyvista")
    r = pv.get_reader(str(result))
    r.reader.UpdateInformation()
    assert r.reader.GetNumberOfSteps() == 3
    with h5py.File(result, "r") as f:
        n_nodes = f.attrs["n_nodes"]
        n_points = n_nodes + 24                 # the nodes, and a far end per interface site (io.mesh)
        last_pts = f["VTKHDF/Points"][2 * n_points:3 * n_points]
        intact_last = f["interface/intact"][-1]
    r.reader.SetStep(2)
    mesh = r.read()
    assert mesh.n_points == n_points
    np.testing.assert_array_equal(np.asarray(mesh.points), last_pts)
    for name in ("velocity", "sxx", "syy", "sxy"):
        assert name in mesh.point_data
    iface = mesh.cell_data["interface"] == 1
    assert iface.sum() == 24
    np.testing.assert_array_equal(mesh.cell_data["intact"][iface], intact_last)
    # Bond cells: bulk bonds join nodes about a apart.
    lines = mesh.cells.reshape(-1, 3)[:, 1:]
    bulk = lines[~iface]
    length = np.linalg.norm(mesh.points[bulk[:, 0]] - mesh.points[bulk[:, 1]], axis=1)
    assert abs(np.median(length) - 1.0) < 0.01 and length.min() > 0.8 and length.max() < 1.2
    # An interface bond joins its top node to the far end standing where its substrate node is: about
    # delta0 = 0.5 a long while intact, a point while broken.
    top, far = lines[iface, 0], lines[iface, 1]
    assert (top < n_nodes).all() and np.array_equal(far, n_nodes + np.arange(24))
    gap = np.linalg.norm(mesh.points[top] - mesh.points[far], axis=1)
    assert (gap[intact_last == 0] == 0).all() and np.all(np.abs(gap[intact_last == 1] - 0.5) < 0.3)
    # Under F_N the top block is compressed: sigma_yy < 0 on average in the top rows.
    assert np.mean(mesh.point_data["syy"][np.asarray(mesh.points)[:, 1] > 4]) < 0


def test_spacetime_png_is_the_bond_record_with_axes(result):
    """The run's picture: inside the axes, the share of yellow (intact) among yellow and white pixels is
    the share of intact bonds in /interface/intact; outside them, dark pixels of tick labels, axis labels
    and a title (a bare raster has none)."""
    import matplotlib.image as mpimg
    png = str(result).replace(".vtkhdf", "_spacetime.png")
    img = (mpimg.imread(png)[..., :3] * 255).round().astype(int)
    yellow = (np.abs(img - np.array([0xF2, 0xC3, 0x00])) <= 2).all(axis=2)
    white = (img >= 253).all(axis=2)
    dark = (img <= 80).all(axis=2)
    with h5py.File(result, "r") as f:
        intact = f["interface/intact"][:int(f["interface"].attrs["frames_written"])]
    rows, cols = np.nonzero(yellow)
    box = (slice(rows.min(), rows.max() + 1), slice(cols.min(), cols.max() + 1))     # the image inside the axes
    share = yellow[box].sum() / (yellow[box].sum() + white[box].sum())
    assert abs(share - intact.mean()) < 0.02, (share, intact.mean())
    outside = dark.copy()
    outside[box] = False
    assert outside[:, :box[1].start].sum() > 50          # y tick labels and the y label, left of the axes
    assert outside[box[0].stop:, :].sum() > 50           # x tick labels and the x label, below
    assert outside[:box[0].start, :].sum() > 50          # the title, above


def test_front_catalogue_on_a_drawn_pattern():
    """Two pulses drawn by hand: one from x = 0 moving right at 0.5 sites per frame,
    one from the far end moving left at 1 site per frame."""
    nf, ns = 60, 40
    t = np.arange(nf) * 0.1
    x = (np.arange(ns) + 0.5) / ns
    intact = np.ones((nf, ns), np.uint8)
    for k in range(nf):
        s = k // 2
        if s < 20:
            intact[k, s] = 0                    # forward pulse, width 1 site
        s2 = ns - 1 - (k - 20)
        if 20 <= k and 25 <= s2:
            intact[k, s2] = 0                   # backward pulse from frame 20
    fr = analysis.fronts(Run.from_arrays({"t": t, "x": x, "intact": intact}))
    assert len(fr) == 2
    a, b = fr
    assert a.direction == 1 and a.x_start == pytest.approx(x[0]) and a.t_start == 0.0
    assert a.speed == pytest.approx((1 / ns) / 0.2, rel=0.05)
    assert b.direction == -1 and b.x_start == pytest.approx(x[-1]) and b.t_start == pytest.approx(2.0)
    assert b.speed == pytest.approx((1 / ns) / 0.1, rel=0.05)
    tb, xb = analysis.first_break({"t": t, "x": x, "intact": intact})
    assert tb == 0.0 and list(xb) == [x[0]]
