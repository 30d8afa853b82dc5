"""Which launcher started this process, whether it fits mpi4py's MPI, and MPI start-up.

Responsible for starting MPI for ``parslip run`` (``start_mpi``) and, before
that, refusing the launcher/library pairings that are known to fail, with one
line that names the ``mpiexec`` to use (exit code 2).  Nothing here runs for
``parslip info`` or ``keys``: they never touch MPI.

A launcher leaves its mark in the environment before MPI_Init; mpi4py can name
its MPI library without initialising it (``rc.initialize = False`` and
``MPI.Get_library_version()``).  Pairings refused before MPI_Init (each seen
on a Debian machine with the ``mpich`` wheel, Debian's MPICH and Open MPI):

- Open MPI's ``mpirun`` (``OMPI_COMM_WORLD_SIZE``) with an MPICH-family
  library: the ``mpich`` wheel aborts every rank inside MPI_Init ("unsupported
  PMI version PMIx", exit 16); other MPICH builds start N one-rank runs that
  all write the same file.
- MPICH's Hydra ``mpiexec`` (``HYDI_CONTROL_FD``, ``PMI_SIZE``) with Open MPI:
  N one-rank runs.
- A PMIx-only launch (``srun --mpi=pmix``, a PRRTE ``prterun``) with the
  ``mpich`` wheel, which is built without PMIx: the same abort as the first.

Everything else starts, srun included (PMI-2 or PMIx, with an mpi4py built
against the site's MPI), and afterwards the world size is compared with the
number of processes the launcher says it started: a mismatch is the signature
of any other wrong pairing, refused the same way.  Only the process the
launcher numbers 0 prints the line, so N processes give one line.
"""
from __future__ import annotations

import os
import re
import shlex
import sys
from dataclasses import dataclass

from ..errors import ConfigError

OPENMPI, MPICH = "Open MPI", "MPICH"
BATCH_STEPS = ("batch", "extern", "4294967294", "4294967295")


def python_command(module: str, *args, ranks: int | None = None) -> list[str]:
    """argv of ``python -m module ARGS`` with this interpreter; with ``ranks``, under ``mpiexec -n ranks``:
    the mpiexec beside the interpreter (the ``mpich`` wheel's, or a venv's), which belongs to the MPI this
    Python's mpi4py loads, else the first on PATH.  Used by everything that starts parslip itself
    (benchmarks, the accuracy study, the paper's runs)."""
    cmd = [sys.executable, "-m", module, *map(str, args)]
    if ranks is None:
        return cmd
    import shutil
    beside = os.path.join(os.path.dirname(sys.executable), "mpiexec")
    mpiexec = beside if os.access(beside, os.X_OK) else (shutil.which("mpiexec") or "mpiexec")
    return [mpiexec, "-n", str(ranks), *cmd]


class LauncherError(ConfigError):
    """A launcher that does not fit mpi4py's MPI; ``speak`` is False on all but the launcher's process 0."""

    def __init__(self, message: str, speak: bool = True):
        super().__init__(message)
        self.speak = speak


@dataclass(frozen=True)
class Launcher:
    name: str               # "Open MPI's mpirun", "MPICH's Hydra mpiexec", "Slurm's srun", "a PMIx launcher"
    family: str | None      # the MPI family it can start, None if any
    size: int | None        # processes it started, if it says
    rank: int | None        # this process's number, if it says
    evidence: str           # the variable that gave it away, as NAME=value
    pmix_only: bool = False  # it offers PMIx and no PMI-1/PMI-2 wire-up


def _int(env, name):
    try:
        return int(env[name])
    except (KeyError, ValueError):
        return None


def detect_launcher(env=None) -> Launcher | None:
    """The launcher that started this process, from its environment; None when started directly."""
    env = os.environ if env is None else env
    pmi_wireup = any(k in env for k in ("PMI_FD", "PMI_PORT", "PMI_RANK"))
    if "OMPI_COMM_WORLD_SIZE" in env:
        return Launcher("Open MPI's mpirun", OPENMPI, _int(env, "OMPI_COMM_WORLD_SIZE"),
                        _int(env, "OMPI_COMM_WORLD_RANK"), f"OMPI_COMM_WORLD_SIZE={env['OMPI_COMM_WORLD_SIZE']}")
    # srun's own steps only: the batch and extern steps (ids 4294967294/5) are one process, whatever SLURM_NTASKS says.
    if "SLURM_STEP_ID" in env and "SLURM_PROCID" in env and env["SLURM_STEP_ID"] not in BATCH_STEPS:
        size = _int(env, "SLURM_STEP_NUM_TASKS")
        return Launcher("Slurm's srun", None, size, _int(env, "SLURM_PROCID"),
                        f"SLURM_STEP_ID={env['SLURM_STEP_ID']}", "PMIX_RANK" in env and not pmi_wireup)
    if "HYDI_CONTROL_FD" in env or "PMI_SIZE" in env:
        key = "PMI_SIZE" if "PMI_SIZE" in env else "HYDI_CONTROL_FD"
        return Launcher("MPICH's Hydra mpiexec", MPICH, _int(env, "PMI_SIZE"), _int(env, "PMI_RANK"),
                        f"{key}={env[key]}")
    if "PMIX_RANK" in env:
        return Launcher("a PMIx launcher", None, None, _int(env, "PMIX_RANK"),
                        f"PMIX_NAMESPACE={env.get('PMIX_NAMESPACE', '?')}", True)
    return None


def library_family(version: str) -> str | None:
    """MPICH (MPICH, Intel MPI, MVAPICH, Cray MPICH: one ABI and launcher protocol), Open MPI, or None."""
    if "Open MPI" in version:
        return OPENMPI
    if re.search(r"MPICH|Intel\(R\) MPI|MVAPICH", version, re.I):
        return MPICH
    return None


def library_name(version: str) -> str:
    """A short name for mpi4py's MPI library: 'MPICH 5.0.2 (the mpich wheel)', 'Open MPI v4.1.4'."""
    m = re.search(r"MPICH Version:\s*(\S+)", version)
    if m:
        return f"MPICH {m.group(1)}" + (" (the mpich wheel)" if is_mpich_wheel(version) else "")
    first = version.strip().splitlines()[0] if version.strip() else "an unknown MPI"
    return first.split(",")[0].strip()


def is_mpich_wheel(version: str) -> bool:
    """The ``mpich`` package from PyPI names its page in the library's version text."""
    return "pypi.org/p/mpich" in version


def _binary_family(path: str) -> str | None:
    real = os.path.basename(os.path.realpath(path)).lower()
    if "openmpi" in real or real in ("orterun", "prterun", "prun"):
        return OPENMPI
    if "mpich" in real or "hydra" in real:
        return MPICH
    return None


def matching_mpiexec(family: str | None, lib_path: str | None, executable: str | None = None) -> str | None:
    """The launcher that belongs to mpi4py's MPI: next to its library's prefix, then next to Python.

    The ``mpich`` wheel puts ``mpiexec`` beside ``python``; Debian puts
    ``mpiexec.mpich`` in /usr/bin while /usr/bin/mpiexec may be Open MPI's,
    hence the check of what each candidate really is.
    """
    names = ("mpiexec", "mpiexec.openmpi", "mpirun.openmpi", "mpirun") if family == OPENMPI \
        else ("mpiexec", "mpiexec.mpich", "mpiexec.hydra", "mpirun")
    dirs = []
    if lib_path:
        d = os.path.dirname(os.path.realpath(lib_path))
        for _ in range(3):       # <prefix>/lib, <prefix>/lib/<triplet>, <prefix>/lib/<triplet>/<mpi>/lib
            dirs.append(os.path.join(d, "bin"))
            d = os.path.dirname(d)
    dirs.append(os.path.dirname(executable or sys.executable))
    other = MPICH if family == OPENMPI else OPENMPI
    for d in dirs:
        for n in names:
            p = os.path.join(d, n)
            if os.path.isfile(p) and os.access(p, os.X_OK) and _binary_family(p) != other:
                return p
    return None


def refusal(launcher: Launcher | None, version: str, mpiexec: str | None, argv=None) -> str | None:
    """Why this launcher cannot start mpi4py's MPI (one line), or None if it is not known to fail."""
    if launcher is None:
        return None
    lib_family = library_family(version)
    wrong_family = launcher.family is not None and lib_family is not None and launcher.family != lib_family
    no_pmix = launcher.pmix_only and is_mpich_wheel(version)
    if not (wrong_family or no_pmix):
        return None
    why = "cannot start it" if wrong_family else "offers only PMIx, which it was built without"
    hint = " (or srun --mpi=pmi2)" if no_pmix and launcher.name == "Slurm's srun" else ""
    return (f"launcher: {launcher.name} started this process ({launcher.evidence}), but mpi4py's MPI is "
            f"{library_name(version)} and {launcher.name} {why}; accepted: {_command(mpiexec, launcher.size, argv)}"
            f"{hint}")


def size_mismatch(launcher: Launcher | None, world_size: int, version: str, mpiexec: str | None,
                  argv=None) -> str | None:
    """After MPI_Init: the launcher started N processes but they did not join one world."""
    if launcher is None or not launcher.size or launcher.size == world_size:
        return None
    return (f"launcher: {launcher.name} started {launcher.size} processes ({launcher.evidence}) but MPI sees "
            f"{world_size} (mpi4py's MPI is {library_name(version)}), so they would be {launcher.size} separate "
            f"runs writing one file; accepted: {_command(mpiexec, launcher.size, argv)}")


def _command(mpiexec: str | None, n: int | None, argv=None) -> str:
    argv = sys.argv if argv is None else argv
    prog = [sys.executable, "-m", "parslip"] + list(argv[1:])
    launcher = mpiexec or "the mpiexec of mpi4py's MPI"
    return f"{launcher} -n {n or 'N'} {shlex.join(prog)}"


def _loaded_libmpi() -> str | None:
    """The MPI library file mapped into this process (Linux), or None."""
    try:
        with open("/proc/self/maps") as f:
            for line in f:
                path = line.split()[-1] if len(line.split()) >= 6 else ""
                if re.search(r"/lib(mpi|mpich|mpi_ibm|mpi_cray)[^/]*\.so", path):
                    return path
    except OSError:
        pass
    return None


def start_mpi(env=None):
    """Check the launcher, initialise MPI, check the world size; returns COMM_WORLD or raises LauncherError."""
    env = os.environ if env is None else env
    import mpi4py
    if "mpi4py.MPI" not in sys.modules:
        # Load the library without MPI_Init, so a wrong launcher is refused
        # before MPI_Init can abort the job; finalize at exit as mpi4py would.
        mpi4py.rc.initialize = False
        mpi4py.rc.finalize = True
    from mpi4py import MPI
    launcher = detect_launcher(env)
    version = MPI.Get_library_version()
    speak = not launcher or not launcher.rank
    mpiexec = None
    if launcher is not None:
        mpiexec = matching_mpiexec(library_family(version), _loaded_libmpi())
    if not MPI.Is_initialized():
        why = refusal(launcher, version, mpiexec)
        if why:
            raise LauncherError(why, speak)
        # parslip's own check below replaces mpi4py's warning about the same thing.
        os.environ.setdefault("MPI4PY_CHECK_MPIEXEC", "0")
        levels = {"single": MPI.THREAD_SINGLE, "funneled": MPI.THREAD_FUNNELED,
                  "serialized": MPI.THREAD_SERIALIZED, "multiple": MPI.THREAD_MULTIPLE}
        if mpi4py.rc.threads:
            MPI.Init_thread(levels.get(mpi4py.rc.thread_level, MPI.THREAD_MULTIPLE))
        else:
            MPI.Init()
    comm = MPI.COMM_WORLD
    why = size_mismatch(launcher, comm.Get_size(), version, mpiexec)
    if why:
        raise LauncherError(why, speak)
    return comm


def world_comm(env=None):
    """COMM_WORLD when a launcher started several processes (MPI starts here, checked as ``start_mpi``
    does), else None: a process started alone, or by ``mpiexec -n 1``, loads no MPI library at all."""
    launcher = detect_launcher(env)
    if launcher is None or launcher.size == 1:
        return None
    return start_mpi(env)
