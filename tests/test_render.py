"""`parslip render` and render.py: real off-screen pictures and movies of a real run.

Checked against the file read through h5py: the picture's size, that the
field shows (many colours, a symmetric scale equal to the P99 of |sxy|), pure
red exactly where intact interface bonds are and not at broken ones, the
movie's frame count, and one line with exit 2 for bad input.
"""
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

pytest.importorskip("pyvista")
from PIL import Image  # noqa: E402  (pillow comes with matplotlib)

import parslip  # noqa: E402
from parslip.plot.render import WINDOW, render_frame  # noqa: E402
from parslip.cli import main  # noqa: E402
from parslip.io.contract import read_snapshot_arrays  # noqa: E402


def snapshot_from_h5(path, k):
    """Snapshot k as the file's readers give it (``io.contract.read_snapshot_arrays``, which reads either
    layout): points, bonds (node ids), sxy, interface and intact flags."""
    s = read_snapshot_arrays(str(path), k)
    return {"t": s["time"], "points": s["points"], "bonds": s["cells"], "sxy": s["sxy"],
            "interface": s["interface"], "intact": s["intact"]}


def pure_red(img):
    """Pixels that are the intact-bond red (255, 0, 0) up to anti-aliasing; no colour map used comes close."""
    a = img.astype(int)
    return (a[..., 0] >= 200) & (a[..., 1] <= 40) & (a[..., 2] <= 40)


@pytest.fixture(scope="module")
def mixed_step(small_run):
    """A snapshot with both intact and broken interface bonds."""
    run = parslip.open(small_run)
    for k in range(len(run.snapshot_times)):
        s = snapshot_from_h5(small_run, k)
        on = s["intact"][s["interface"] == 1]
        if 0 < on.sum() < on.size:
            return k
    pytest.fail("no snapshot of the small run has intact and broken interface bonds at once")


def test_cli_png_is_a_real_picture_of_the_field(small_run, mixed_step, tmp_path, capsys):
    s = snapshot_from_h5(small_run, mixed_step)
    png = tmp_path / "f.png"
    assert main(["render", small_run, "--field", "sxy", "--time", f"{s['t'] + 0.01:.6f}", "-o", str(png)]) == 0
    assert f"snapshot {mixed_step} of" in capsys.readouterr().out
    with open(png, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    img = np.asarray(Image.open(png).convert("RGB"))
    assert img.shape == (WINDOW[1], WINDOW[0], 3)
    colours = np.unique(img.reshape(-1, 3), axis=0)
    assert len(colours) > 200, "the field does not show: too few colours"
    white = np.all(img == 255, axis=-1).mean()
    assert 0.2 < white < 0.95


def test_scale_is_symmetric_p99_and_red_marks_intact_bonds(small_run, mixed_step, tmp_path):
    s = snapshot_from_h5(small_run, mixed_step)
    fr = render_frame(parslip.open(small_run), "sxy", s["t"], str(tmp_path / "f.png"))
    assert fr.step == mixed_step and fr.time == s["t"]
    lim = np.percentile(np.abs(s["sxy"]), 99)
    assert fr.clim == pytest.approx((-lim, lim), rel=1e-12)
    red = pure_red(np.asarray(Image.open(fr.path).convert("RGB")))
    iface = np.flatnonzero(s["interface"] == 1)
    near = np.zeros_like(red)
    checked = {0: 0, 1: 0}
    for c in iface:
        a, b = s["points"][s["bonds"][c]]
        mid = 0.5 * (a + b)
        x, y = (int(round(q)) for q in fr.pixel(mid))
        window = red[max(y - 3, 0):y + 4, max(x - 3, 0):x + 4]
        intact = int(s["intact"][c])
        assert window.any() == bool(intact), f"interface bond {c} (intact={intact}) at pixel {x}, {y}"
        checked[intact] += 1
        # Every red pixel must belong to some intact bond: mark the pixels along each intact one.
        if intact:
            for q in np.linspace(0, 1, 30):
                px, py = (int(round(u)) for u in fr.pixel(a + q * (b - a)))
                near[max(py - 4, 0):py + 5, max(px - 4, 0):px + 5] = True
    assert checked[0] > 0 and checked[1] > 0
    assert red.sum() > 0 and not (red & ~near).any(), "red pixels away from intact interface bonds"


@pytest.mark.parametrize("ext", [".mp4", ".gif"])
def test_movie_has_one_frame_per_snapshot(small_run, ext, tmp_path):
    out = tmp_path / f"m{ext}"
    assert main(["render", small_run, "--field", "sxy", "--movie", str(out), "--fps", "2"]) == 0
    with h5py.File(small_run, "r") as f:
        n = len(f["VTKHDF/Steps/Values"])
    if ext == ".gif":
        im = Image.open(out)
        assert (im.n_frames, im.size) == (n, WINDOW)
    else:
        import imageio_ffmpeg
        frames, secs = imageio_ffmpeg.count_frames_and_secs(str(out))
        assert frames == n and secs == pytest.approx(n / 2, abs=0.51)


@pytest.mark.parametrize("case", ["field", "time", "missing", "text", "h5", "movie-ext", "clim"])
def test_bad_input_is_one_line_and_exit_2(case, small_run, tmp_path, capsys):
    run = small_run
    args = {"field": ["--field", "stress"], "time": ["--time", "1e3"], "movie-ext": ["--movie", str(tmp_path / "m.avi")],
            "clim": ["--clim", "-1"]}.get(case, [])
    if case == "missing":
        run = str(tmp_path / "none.vtkhdf")
    elif case == "text":
        run = str(tmp_path / "t.vtkhdf")
        open(run, "w").write("not HDF5")
    elif case == "h5":
        run = str(tmp_path / "other.h5")
        with h5py.File(run, "w") as f:
            f["x"] = np.arange(3)
    assert main(["render", run, *args, "-o", str(tmp_path / "x.png")] if case != "movie-ext"
                else ["render", run, *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("parslip: error: ") and err.count("\n") == 1, err
    assert "accepted" in err
    assert not os.path.exists(tmp_path / "x.png")


def test_snapshot_script_renders_through_render_py(small_run, tmp_path):
    png = tmp_path / "s.png"
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    # A script's own folder heads sys.path, not the checkout: name the checkout, whatever is installed.
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")])))
    p = subprocess.run([sys.executable, os.path.join(root, "postprocess", "snapshot.py"), small_run, "--step", "1",
                        "--field", "syy", "--png", str(png)], capture_output=True, text=True, timeout=300, env=env)
    assert p.returncode == 0, p.stderr
    assert Image.open(png).size == WINDOW and "step 1 of" in p.stdout


def _without_pyvista(tmp_path, *argv):
    """`parslip ARGV` in a Python where importing pyvista fails (as where the [viz] extra is missing)."""
    import subprocess
    import sys

    from helpers import cli_env
    code = ("import sys; sys.modules['pyvista'] = None; from parslip.cli.main import main; "
            f"sys.exit(main({list(map(str, argv))!r}))")
    return subprocess.run([sys.executable, "-c", code], env=cli_env(), capture_output=True, text=True, timeout=300,
                          cwd=tmp_path)


def test_without_the_viz_extra_render_says_which_extra(small_run, tmp_path):
    p = _without_pyvista(tmp_path, "render", small_run, "--field", "sxy", "-o", tmp_path / "a.png")
    assert p.returncode == 2, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "needs pyvista" in lines[0] and "[viz]" in lines[0], p.stderr


def test_without_the_viz_extra_figures_skip_the_maps_and_say_so(small_run, tmp_path):
    p = _without_pyvista(tmp_path, "figures", small_run, "-o", tmp_path / "figs")
    assert p.returncode == 0, p.stderr
    assert "Traceback" not in p.stderr
    skipped = [ln for ln in p.stderr.splitlines() if "stress maps skipped" in ln]
    assert len(skipped) == 1 and "[viz]" in skipped[0], p.stderr
    assert (tmp_path / "figs" / "spacetime.png").exists() and not list((tmp_path / "figs").glob("map_*"))
