"""The model picture drawn from a scene's own geometry (``parslip draw``, the docs' model figure).

It draws a small scene and looks at the pixels: the lattice covers a good part of the picture, and the
interface bond red, the re-formed bond green and the drive orange are all there.  The command line refuses
a missing scene, a bad key and an unwritable output with exit 2 and one line.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SMALL = """\
[lattice]
top_rows = 4
top_cols = 12
bottom_rows = 6
bottom_cols = 20

[drive]
mode = "shear"
"""


def _cli(*args, cwd):
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "MPLBACKEND": "Agg", "HOME": str(cwd)}
    return subprocess.run([sys.executable, "-m", "parslip", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=120, env=env)


def _has_colour(img, hex_colour, tol=0.08, at_least=30):
    rgb = np.array([int(hex_colour[i:i + 2], 16) / 255 for i in (1, 3, 5)])
    return int((np.abs(img[..., :3] - rgb).max(axis=-1) < tol).sum()) >= at_least


def test_draw_writes_a_picture_of_the_scene(tmp_path):
    from matplotlib.image import imread

    from parslip.plot import scene_picture as sp

    scene = tmp_path / "small.toml"
    scene.write_text(SMALL)
    r = _cli("draw", scene, "-o", tmp_path / "small.png", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    png = tmp_path / "small.png"
    assert png.is_file() and png.stat().st_size > 20_000
    img = imread(png)
    h, w = img.shape[:2]
    assert w > 600 and h > 300, img.shape
    ink = (img[..., :3].min(axis=-1) < 0.9).mean()
    assert 0.03 < ink < 0.6, f"{ink:.3f} of the picture is drawn on"
    for name, colour in (("interface bond", sp.BOND), ("re-formed bond", sp.REFORMED), ("drive", sp.DRIVE),
                         ("block node", sp.NODE_TOP), ("load", sp.LOAD)):
        assert _has_colour(img, colour), f"no {name} ({colour}) in the picture"


def test_draw_picture_of_the_docs_scene_as_png_bytes():
    from parslip.plot import scene_picture as sp

    data = sp.scene_png(sp.DOCS_SCENE)
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_draw_refuses_bad_input_with_exit_2_and_one_line(tmp_path):
    r = _cli("draw", tmp_path / "missing.toml", cwd=tmp_path)
    assert r.returncode == 2, r.stdout + r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "missing.toml" in lines[0] and lines[0].startswith("parslip: error:"), r.stderr
    assert not (tmp_path / "missing_scene.png").exists()

    scene = tmp_path / "small.toml"
    scene.write_text(SMALL)
    r = _cli("draw", scene, "--set", "lattice.top_cols=3", cwd=tmp_path)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "top_cols" in r.stderr, r.stderr
    r = _cli("draw", scene, "-o", tmp_path / "no" / "such" / "dir.png", cwd=tmp_path)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
