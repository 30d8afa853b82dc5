"""Fixtures shared by the analysis tests: one short real push run, made once per session.

Also puts the MPI launcher that matches mpi4py's MPI first on PATH for the whole suite, points every
process at one kernel cache, and fills that cache in the background while the session starts.
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


def _one_kernel_cache_for_the_session() -> None:
    """Point every process the tests start at the kernel cache this process uses (NUMBA_CACHE_DIR).

    Without it the kernels' folder follows PARSLIP_CACHE_DIR, which tests set to a fresh directory for an
    omega_max cache of their own: each of their subprocesses, and each rank of an MPI run at once,
    then compiled the time loop from nothing (about 40 s of a core apiece, minutes on a loaded host).
    The folder is keyed by the kernels' sources (io.cache.kernel_cache_dir), so sharing it never
    serves a stale kernel.  A NUMBA_CACHE_DIR set by the caller is kept.
    """
    from parslip.io.cache import kernel_cache_dir
    os.environ.setdefault("NUMBA_CACHE_DIR", os.path.dirname(kernel_cache_dir()))


_one_kernel_cache_for_the_session()

# Kernel variants the tests use that the first test file (one rank, float64, in this process) does not
# compile: the time loop in float32, then on several ranks, one after the other.  Each scene is SMALL for
# 0.1 l/c_r.
WARM_UPS = ((1, ("--set", "time.precision=float32")), (2, ()))
_warming = []


def pytest_sessionstart(session):
    """Fill the kernel cache in the background while pytest collects and the first tests run.

    On a cold cache (a fresh clone) the first run of each loop variant compiles it: about 150 s of a
    core for one rank in float64 (the first test, in this process), 135 s for float32, and 30 s per
    rank for the multi-rank variant once the one-rank kernels are in the cache (each rank compiles the
    exchange's specialisations; from a cold cache every rank compiles everything, 150 s each).  Left
    to the tests, the multi-rank variant is compiled by every rank of the first MPI test at once
    (three ranks on two cores), under that test's hard time limit.  Started here, in one chain on the
    core the first test leaves free, float32 first and the ranks when most of the one-rank kernels
    are stored: on this 2-core machine, from a fresh clone, started together they took 365 s of the
    first test's wall time and the suite 1134 s; in a chain 124 s and 779 s (4d9b95a).  On a warm cache each warm-up only loads the loop.  A test
    that needs a variant before its warm-up has stored it compiles it as before, so the warm-ups
    change no result and no test waits for them.  Started for the suite or a folder of it only: a run
    of chosen test files needs some of these variants at most, and a warm-up it does not need would
    take a core from it.  Not started in the per-test pytest processes mpi-pytest launches, nor in
    pytest-xdist's workers (the README's command runs two; their controller starts the chain once), nor
    without the mpich wheel's launcher.
    """
    import shutil
    import subprocess
    import tempfile

    from helpers import WHEEL_MPIEXEC, cli_command, cli_env
    chosen = [a for a in session.config.args if not os.path.isdir(a)]
    worker = "PYTEST_XDIST_WORKER" in os.environ           # pytest-xdist's workers: their controller warms up
    if chosen or worker or "_PYTEST_MPI_CHILD_PROCESS" in os.environ or not WHEEL_MPIEXEC:
        return
    import shlex
    d = tempfile.mkdtemp(prefix="parslip-warm-")
    sc = os.path.join(d, "warm.toml")
    with open(sc, "w") as fh:
        fh.write(small_toml(**{"drive.duration": 0.1, "output.snapshots": 0}))
    chain = "; ".join(shlex.join(cli_command(n, "run", sc, "--out", os.path.join(d, f"w{k}.vtkhdf"), "--no-png",
                                             "--quiet", *sets)) for k, (n, sets) in enumerate(WARM_UPS))
    _warming.append(subprocess.Popen(["sh", "-c", chain], env=cli_env(), stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL, start_new_session=True))
    _warming.append(lambda: shutil.rmtree(d, ignore_errors=True))


def pytest_sessionfinish(session, exitstatus):
    """End warm-ups still running (a short session) with their ranks, and remove their folder."""
    import signal

    from helpers import ranks_below
    for w in _warming:
        if callable(w):
            w()
        elif w.poll() is None:
            for pid in ranks_below(w.pid):          # in sessions of their own under Hydra
                try:
                    os.kill(pid, signal.SIGKILL)
                except OSError:
                    pass
            os.killpg(w.pid, signal.SIGKILL)
            w.wait()

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


@pytest.fixture(scope="session")
def docs_site(tmp_path_factory):
    """The documentation site, built once per session with ``mkdocs build --strict`` (tests/test_docs.py and
    tests/test_site.py read it); the build fails the test with its output on any warning."""
    import pathlib
    import re
    import subprocess
    import sys

    root = pathlib.Path(__file__).resolve().parent.parent
    out = tmp_path_factory.mktemp("site")
    try:
        import mkdocs  # noqa: F401
    except ImportError:
        pytest.fail('mkdocs is not installed: python -m pip install -e ".[docs]" (tests/install.sh does)')
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                        str(root / "mkdocs.yml"), "--site-dir", str(out)],
                       cwd=root, capture_output=True, text=True, timeout=600)
    log = r.stdout + r.stderr
    warnings = [line for line in log.splitlines() if re.search(r"\bWARNING\b|Warning:", line)]
    assert r.returncode == 0 and not warnings, f"mkdocs build --strict failed (exit {r.returncode}):\n{log}"
    return out
