"""Shared builders for the tests: scenes from dotted overrides, state access by global id,
drawn interface records, and the command line run on several ranks with either output writer."""
from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from parslip.engine.reference_engine import Simulation as ReferenceSimulation
from parslip.engine.simulation import Simulation
from parslip.model.lattice import TOP
from parslip.scene.derive import derive
from parslip.scene.load import resolve

# A free block at rest: no substrate, no load, no drive, no damping.
FREE_BLOCK = {"lattice.bottom_rows": 0, "drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0,
              "load.FN": 0.0, "time.zeta": 0.0, "output.snapshots": 0}

# The paper's set-up shrunk to seconds: bonds break and re-form within a few l/c_r.
SMALL = {"lattice.top_rows": 4, "lattice.top_cols": 24, "lattice.bottom_rows": 4, "lattice.bottom_cols": 40,
         "load.ramp": 0.5, "load.settle": 2.0, "drive.v0": 0.02, "drive.duration": 6.0,
         "output.snapshots": 3}


def small_toml(**kw) -> str:
    """SMALL (plus overrides) as scene-file text, for tests that go through the command line."""
    from parslip.scene.schema import to_toml
    over = dict(SMALL)
    over.update(kw)
    return to_toml(over)


def scene(**kw) -> dict:
    """Resolved scene from keyword overrides: scene(**{"drive.v0": 1e-2})."""
    return resolve({}, list(kw.items()))


def simulation(base: dict | None = None, **kw) -> Simulation:
    over = dict(base or {})
    over.update(kw)
    return Simulation(derive(scene(**over)))


def set_field(sim: Simulation, fn) -> None:
    """u = fn(x, y) -> (ux, uy) on every node, at rest (u(n-1) = u(n))."""
    nd = sim.state.nodes()
    ux, uy = fn(nd["x"], nd["y"])
    sim.set_u(np.stack([ux, uy], axis=1))


def row_nodes(sim: Simulation, row: int) -> np.ndarray:
    """Indices (into the arrays in global id order) of a row of the top block, sorted by x."""
    nd = sim.state.nodes()
    idx = np.flatnonzero((nd["block"] == TOP) & (nd["row"] == row))
    return idx[np.argsort(nd["x"][idx])]


def reference(sim: Simulation) -> ReferenceSimulation:
    """The first engine's plain per-node implementation, holding a copy of ``sim``'s state (one rank).

    An independent implementation of the same model: its kernels gather
    neighbours by index and sum each bond's force on its own.
    """
    ref = ReferenceSimulation(sim.setup)
    assert np.array_equal(ref.layout.nodes["gid"][:ref.n_owned], sim.state.gid)
    ref.u[:ref.n_owned] = sim.u
    ref.u_prev[:ref.n_owned] = sim.u_prev
    ref.partner[ref.own_sites] = sim.state.owned_partner()
    ref.x0[ref.own_sites] = sim.state.owned_x0()
    ref.u_drive0[:ref.n_owned] = sim.checkpoint_slab().arrays["drive0"]      # where the driven face started
    ref.n = sim.n
    return ref


# --- drawn interface records with known rupture fronts (front detector, paper table, accuracy) ---

DT = 0.05          # l/c_r per frame
NS = 60            # sites: dx = 1/60 l


def blank(nf):
    x = (np.arange(NS) + 0.5) / NS
    return {"t": np.arange(nf) * DT, "x": x, "intact": np.ones((nf, NS), np.uint8),
            "ux": np.zeros((nf, NS)), "uy": np.zeros((nf, NS))}


def draw(iface, k0, s0, d, fps, width, slip, crack=False, sites=None, slip_v=0.0):
    """Tip at site s0 + d*j from frame k0 + fps*j; the `width` sites behind it broken (a crack keeps all).

    A pulse adds `slip` to ux (and `slip_v` to uy) at a site from the frame it re-bonds; a crack from the
    frame it breaks.  Returns the arrival frames.
    """
    nf = len(iface["t"])
    n = sites or (NS - s0 if d > 0 else s0 + 1)
    arr = k0 + fps * np.arange(n)
    for k in range(k0, nf):
        j = min((k - k0) // fps, n - 1)
        tip = s0 + d * j
        back = j if crack else min(width - 1, j)
        lo, hi = sorted((tip, tip - d * back))
        iface["intact"][k, lo:hi + 1] = 0
        if not crack and j == n - 1 and k >= arr[-1] + fps:
            break                                   # the pulse has left through the far edge
    for j in range(n):
        s = s0 + d * j
        on = np.flatnonzero(iface["intact"][arr[j]:, s] == 1)
        k_slip = arr[j] if crack else arr[j] + on[0]
        iface["ux"][k_slip:, s] += slip
        iface["uy"][k_slip:, s] += slip_v
    return arr


# ---------------------------------------------------------------- the command line under MPI --
# Two ways to run parslip on several ranks, each with its own MPI and its own writer:
#   "gather": this Python (PyPI's serial h5py) under the mpich wheel's mpiexec;
#   "mpio":   the venv slurm/install-parallel-hdf5.sh builds (h5py with MPI) under
#             Debian's mpiexec.mpich, the launcher of the MPICH that venv loads.
REPO = Path(__file__).resolve().parents[1]
MPIO_VENV = Path(os.environ.get("PARSLIP_MPIO_VENV") or REPO / ".venv-mpio")
MPIO_PYTHON = str(MPIO_VENV / "bin" / "python")
MPIO_MPIEXEC = shutil.which("mpiexec.mpich")


def _wheel_mpiexec():
    """The mpich wheel installs its mpiexec beside the interpreter; PATH may hold Open MPI's first."""
    beside = os.path.join(os.path.dirname(sys.executable), "mpiexec")
    return beside if os.access(beside, os.X_OK) else shutil.which("mpiexec")


WHEEL_MPIEXEC = _wheel_mpiexec()
WRITERS = ("gather", "mpio")


@functools.cache
def mpio_missing() -> str | None:
    """Why the mpio venv cannot run here, or None when it can."""
    if not MPIO_MPIEXEC:
        return "no mpiexec.mpich (Debian's mpich package)"
    if not os.access(MPIO_PYTHON, os.X_OK):
        return f"no {MPIO_PYTHON}"
    p = subprocess.run([MPIO_PYTHON, "-c", "import h5py; assert h5py.get_config().mpi"], capture_output=True,
                       text=True, timeout=120)
    return None if p.returncode == 0 else f"h5py in {MPIO_VENV} has no MPI: {p.stderr.strip()[-200:]}"


def unavailable(what: str) -> None:
    """Skip a test that needs what tests/install.sh provides; in CI, where it has run, fail instead."""
    msg = f"{what}; run `bash tests/install.sh`"
    if os.environ.get("CI") == "true":
        pytest.fail(msg)
    pytest.skip(msg)


def require(writer: str) -> None:
    """Skip (or, in CI, fail) a test whose writer cannot run here."""
    why = mpio_missing() if writer == "mpio" else (None if WHEEL_MPIEXEC else "no mpiexec (the mpich wheel)")
    if why:
        unavailable(f"{writer} writer unavailable: {why}")


def cli_command(n: int, *args, writer: str = "gather") -> list[str]:
    """argv of `parslip ARGS` on n ranks with the given writer's MPI and Python."""
    require(writer)
    mpiexec, python = (MPIO_MPIEXEC, MPIO_PYTHON) if writer == "mpio" else (WHEEL_MPIEXEC, sys.executable)
    return [mpiexec, "-n", str(n), python, "-m", "parslip", *map(str, args)]


def cli_env(**extra) -> dict:
    """The environment for cli_command: this checkout first on the path, whichever Python runs it."""
    env = dict(os.environ, **extra)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO)] + [p for p in [env.get("PYTHONPATH")] if p])
    return env


def run_limited(cmd, env=None, timeout: float = 300, cwd=None) -> subprocess.CompletedProcess:
    """Run ``cmd`` in its own process group under a hard time limit: past it every process of the group
    (the launcher and all its ranks) is killed and the test fails as a hang, without leaving ranks behind."""
    import signal
    proc = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        pytest.fail(f"hung: {' '.join(map(str, cmd))} ran past its limit of {timeout:g} s\n"
                    f"stderr (last 3000 characters):\n{err[-3000:]}")
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def run_cli(n: int, *args, writer: str = "gather", env: dict | None = None, timeout: float = 300):
    """`parslip ARGS` on n ranks, as a user starts it, under a hard time limit (a hang fails the test)."""
    return run_limited(cli_command(n, *args, writer=writer), env=cli_env(**(env or {})), timeout=timeout)


def reference_run(directory, scene: dict, *sets: str):
    """A reference for a test module: ``scene`` (small_toml keys) written to DIRECTORY/s.toml and run to
    the end on one rank with the gathering writer; returns (scene path, output path)."""
    require("gather")
    sc = directory / "s.toml"
    sc.write_text(small_toml(**scene))
    out = directory / "ref.vtkhdf"
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", *sets)
    assert p.returncode == 0, p.stderr
    return sc, out


def assert_extension_is_the_run(sc, out, ref: dict, half: float, n_first: int, n_then: int) -> None:
    """Scene ``sc`` run to drive.duration = ``half`` on ``n_first`` ranks, then continued from its end
    checkpoint to the scene's own duration on ``n_then`` ranks: its interface record must be ``ref``'s (the
    datasets of the uninterrupted run) bit for bit (snapshot times depend on the duration)."""
    p = run_cli(n_first, "run", sc, "--out", out, "--no-png", "--quiet", "--set", f"drive.duration={half!r}")
    assert p.returncode == 0, p.stderr
    p = run_cli(n_then, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", str(out) + ".ckpt.h5")
    assert p.returncode == 0, p.stderr
    got, attrs = datasets(out)
    assert attrs["status"] == "complete"
    for name in ref:
        if name.startswith("interface/"):
            assert got[name].tobytes() == ref[name].tobytes(), name


def datasets(path) -> tuple[dict, dict]:
    """Every dataset of an HDF5 file by name, and its root attributes (with the status, as text)."""
    import h5py

    from parslip.io.contract import STATUS, read_status
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[...]) if isinstance(obj, h5py.Dataset) else None)
        attrs = dict(f.attrs)
        attrs[STATUS] = read_status(f)
    return out, attrs


def ranks_below(launcher_pid) -> list[int]:
    """The parslip processes below the launcher (the ranks, not its proxies).  Found by
    parent links: Debian's Hydra puts each proxy and rank in a session of its own."""
    parent = {}
    for d in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{d}/stat") as f:
                parent[int(d)] = int(f.read().rsplit(")", 1)[1].split()[1])
        except OSError:
            pass
    below, todo = [], [launcher_pid]
    while todo:
        pid = todo.pop()
        kids = [p for p, pp in parent.items() if pp == pid]
        below += kids
        todo += kids
    ranks = []
    for pid in below:
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if b"\0-m\0parslip\0" in f.read():
                    ranks.append(pid)
        except OSError:
            pass
    return ranks


def run_small(tmp_path, name: str, n: int = 1, extra=(), timeout: float = 200, **sets):
    """SMALL (plus the dotted overrides ``sets``, no snapshots unless set) run by the command line on n ranks
    with the gathering writer: (the scene file, the output file), the run checked to have ended well."""
    require("gather")
    sc = tmp_path / f"{name}.toml"
    sc.write_text(small_toml(**{"output.snapshots": 0, **sets}))
    out = tmp_path / f"{name}_{n}.vtkhdf"
    p = run_cli(n, "run", sc, "--out", out, "--no-png", "--quiet", "--watchdog", "30", *extra, timeout=timeout)
    assert p.returncode == 0, p.stderr
    return sc, out
