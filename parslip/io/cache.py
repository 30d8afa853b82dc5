"""Results worth keeping between runs: omega_max of a lattice, on disk.

The highest eigenfrequency of a lattice (``model.stability.omega_max``)
takes about a second of Lanczos iterations for the paper's scenes and a
minute for the largest lattices it serves exactly; it depends only on the
geometry and the stiffnesses.  It is kept in a JSON file under
``$PARSLIP_CACHE_DIR`` (default ``$XDG_CACHE_HOME/parslip``, else
``~/.cache/parslip``), keyed by those inputs, so a sweep or a rerun starts at
once.  The value stored is the value computed, so a cached run is the same
run.  VERSION 2: omega_max rounded up to 24 significant bits, the same on
every host (``model.stability``); version 1's unrounded values are never
served, as VERSION is part of every key.  Only the process that derives the scene (rank 0) reads or writes it;
an unwritable cache is skipped silently.
"""
from __future__ import annotations

import glob
import hashlib
import json
import os
import tempfile

VERSION = 2          # 2: omega_max rounded up to stability.OMEGA_BITS bits


def cache_dir() -> str:
    d = os.environ.get("PARSLIP_CACHE_DIR")
    if d:
        return d
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "parslip")


def _path() -> str:
    return os.path.join(cache_dir(), "omega_max.json")


def key(**inputs) -> str:
    return hashlib.sha256(json.dumps([VERSION, inputs], sort_keys=True).encode()).hexdigest()[:32]


def lookup(k: str):
    try:
        with open(_path()) as f:
            entry = json.load(f).get(k)
        return (float(entry[0]), str(entry[1])) if entry else None
    except (OSError, ValueError, TypeError, IndexError):
        return None


def store(k: str, value: tuple[float, str]) -> None:
    """Add one entry; written to a temporary file and renamed, so a reader never sees half a file."""
    path = _path()
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        try:
            with open(path) as f:
                table = json.load(f)
        except (OSError, ValueError):
            table = {}
        table[k] = [repr(float(value[0])), value[1]]
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=".omega-", suffix=".json")
        with os.fdopen(fd, "w") as f:
            json.dump(table, f)
        os.replace(tmp, path)
    except OSError:
        pass


# The subpackages whose code numba compiles into the time loop (kernels, the exchange, the law's codes).
KERNEL_PACKAGES = ("engine", "parallel", "model")


def kernel_cache_dir() -> str:
    """Where numba keeps the compiled kernels: $NUMBA_CACHE_DIR (else this cache's "numba" folder), in a
    subfolder named by a hash of the kernels' sources and the numba and Python versions.

    numba checks a cached function against its own file's time stamp only, not the files of the functions
    it calls: the compiled time loop (engine/loop.py) would keep the old interface kernel after
    engine/kernels/interface.py changed (seen here: results that differed from the source's).  A new
    folder for every change of any of those sources rules that out."""
    import sys
    h = hashlib.sha256(f"{sys.version_info[:2]}".encode())
    try:
        import numba
        h.update(numba.__version__.encode())
    except ImportError:
        pass
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    for sub in KERNEL_PACKAGES:
        for path in sorted(glob.glob(os.path.join(root, sub, "**", "*.py"), recursive=True)):
            h.update(os.path.relpath(path, root).encode())
            with open(path, "rb") as fh:
                h.update(fh.read())
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(cache_dir(), "numba")
    return os.path.join(base, f"parslip-{h.hexdigest()[:16]}")


def use_kernel_cache() -> None:
    """Point numba's cache at ``kernel_cache_dir()``; called before any kernel is compiled or loaded."""
    import numba
    numba.config.CACHE_DIR = kernel_cache_dir()
