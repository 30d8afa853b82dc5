"""Fixtures shared by the analysis tests: one short real push run, made once per session."""
import os

import pytest

from helpers import small_toml

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

# SMALL driven long enough for three to four pulses from the rear edge.
SMALL_RUN = {"drive.duration": 10.0, "output.snapshots": 4}


@pytest.fixture(scope="session")
def small_run(tmp_path_factory):
    """Path of a short push run on the SMALL lattice (24 sites, v0/c_r = 0.02, 10 l/c_r)."""
    from parslip.cli import main
    d = tmp_path_factory.mktemp("small_run")
    sc = d / "small.toml"
    sc.write_text(small_toml(**SMALL_RUN))
    out = d / "small.vtkhdf"
    assert main(["run", str(sc), "--out", str(out), "--quiet", "--no-png"]) == 0
    return str(out)
