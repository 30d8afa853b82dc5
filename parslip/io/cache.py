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


# What marks a module whose code numba compiles (the kernels, the exchange, the MPI symbols), and the
# subpackages that hold the time loop's (a benchmark's own kernels elsewhere do not key the loop's cache).
COMPILED_MARKS = ("@njit", "njit(", "@overload", "@intrinsic", "ExternalFunction")
KERNEL_PACKAGES = ("engine", "parallel", "model")


def kernel_sources(root: str) -> list[str]:
    """The package's modules the time loop's compiled code depends on: every module with compiled code in
    ``KERNEL_PACKAGES``, and every package module they import, transitively (their functions are compiled
    in, their constants frozen in).
    A module only Python runs (the run's orchestration, the layouts' bookkeeping, the writers) is not
    among them, so changing it does not make numba compile the loop again."""
    import ast
    sources = {}
    for path in glob.glob(os.path.join(root, "**", "*.py"), recursive=True):
        with open(path, encoding="utf-8") as fh:
            sources[path] = fh.read()

    def imported(path):
        base, out = os.path.dirname(path), set()
        for node in ast.walk(ast.parse(sources[path])):
            if isinstance(node, ast.ImportFrom) and node.level > 0:
                d = base
                for _ in range(node.level - 1):
                    d = os.path.dirname(d)
                mod = os.path.join(d, *(node.module.split(".") if node.module else []))
                for c in [mod + ".py", os.path.join(mod, "__init__.py")] + [os.path.join(mod, a.name + ".py")
                                                                           for a in node.names]:
                    if c in sources:
                        out.add(c)
        return out

    inside = tuple(os.path.join(root, sub) + os.sep for sub in KERNEL_PACKAGES)
    todo = [p for p, text in sources.items() if p.startswith(inside) and any(m in text for m in COMPILED_MARKS)]
    seen = set(todo)
    while todo:
        for q in imported(todo.pop()) - seen:
            seen.add(q)
            todo.append(q)
    return sorted(seen)


def kernel_cache_dir() -> str:
    """Where numba keeps the compiled kernels: $NUMBA_CACHE_DIR (else this cache's "numba" folder), in a
    subfolder named by a hash of the kernels' sources (``kernel_sources``) and the numba and Python versions.

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
    for path in kernel_sources(root):
        h.update(os.path.relpath(path, root).encode())
        with open(path, "rb") as fh:
            h.update(fh.read())
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(cache_dir(), "numba")
    return os.path.join(base, f"parslip-{h.hexdigest()[:16]}")


def use_kernel_cache() -> None:
    """Point numba's cache at ``kernel_cache_dir()``; called before any kernel is compiled or loaded."""
    import numba
    numba.config.CACHE_DIR = kernel_cache_dir()


COEFFICIENTS = "coefficients.json"


def load_coefficients() -> dict | None:
    """The scaling model's coefficients `parslip bench` measured on this host (``store_coefficients``), or None."""
    try:
        with open(os.path.join(cache_dir(), COEFFICIENTS)) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def store_coefficients(values: dict) -> str:
    """Keep the scaling model's measured coefficients for `parslip info` (atomic replace); returns the path."""
    path = os.path.join(cache_dir(), COEFFICIENTS)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=".coefficients-", suffix=".json")
    with os.fdopen(fd, "w") as f:
        json.dump(values, f, indent=1)
    os.replace(tmp, path)
    return path
