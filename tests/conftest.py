"""Fixtures shared by the analysis tests: one short real push run, made once per session.

Also puts the MPI launcher that matches mpi4py's MPI first on PATH for the whole suite.
"""
import os
import sysconfig

import pytest

from helpers import small_toml

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def _mpi_launcher_first_on_path() -> None:
    """Make ``mpiexec`` (mpi-pytest's and the tests' ``shutil.which``) the launcher of mpi4py's MPI.

    The ``mpich`` wheel installs its ``mpiexec`` in this Python's scripts folder.
    Debian's paraview, installed for the pvpython tests, brings Open MPI's
    ``mpirun``/``mpiexec`` into /usr/bin; a launcher of another MPI starts n
    singleton jobs of size 1 instead of one job of size n.  Where no launcher
    sits beside Python (a cluster's own MPI), PATH stays as the environment set it.
    """
    scripts = sysconfig.get_path("scripts")
    if os.access(os.path.join(scripts, "mpiexec"), os.X_OK):
        os.environ["PATH"] = scripts + os.pathsep + os.environ.get("PATH", "")


_mpi_launcher_first_on_path()

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


# Long enough that a signal, a fault or a hook lands inside the time loop (a million steps, several seconds
# on 2 ranks); frames flushed every 64 so that writes happen throughout.
LONG = {"drive.duration": 3000.0, "drive.v0": 0.0005, "output.buffer_frames": 64}


@pytest.fixture
def long_scene(tmp_path):
    """A SMALL scene driven for a million steps (see LONG)."""
    sc = tmp_path / "long.toml"
    sc.write_text(small_toml(**LONG))
    return sc
