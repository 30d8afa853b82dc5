"""MPI calls from compiled code: functions of the MPI library mpi4py uses.

numba code calls ``MPI_Start``, ``MPI_Startall`` (the exchange's persistent requests, made once per plan by
mpi4py), ``MPI_Waitall``, ``MPI_Testall`` and ``MPI_Allreduce`` (and ``MPI_Isend``, ``MPI_Irecv``) by
symbol name.  The library mpi4py loaded is made visible
to the JIT linker (``load_library_permanently``), so the compiled loop links
against exactly the MPI that mpi4py initialised, and numba can cache it:
nothing process-specific (no ctypes pointers) is baked into the code.
Handles (communicator, datatypes, the MAX operation) are passed in as
integers at run time, which serves both MPICH (int handles) and Open MPI
(pointer handles).

Only ``parallel.halo_mpi`` imports this module (and so loads the MPI library); kernels never see MPI.
"""
from __future__ import annotations

import ctypes.util
import os

import numpy as np
from numba import types

from mpi4py import MPI


def _libmpi_path() -> str:
    """Path of the MPI library mpi4py loaded into this process."""
    try:
        with open("/proc/self/maps") as f:
            for line in f:
                path = line.split()[-1]
                name = os.path.basename(path)
                if name.startswith(("libmpi.so", "libmpi_mpifh", "libmpich.so")) and name.split(".so")[0] in (
                        "libmpi", "libmpich"):
                    return path
    except OSError:
        pass
    return ctypes.util.find_library("mpi") or ctypes.util.find_library("mpich") or ""


def _load():
    import llvmlite.binding as llb
    path = _libmpi_path()
    if not path:
        raise ImportError("parslip: cannot find the MPI library mpi4py uses; compiled halo exchange unavailable")
    llb.load_library_permanently(path)
    return path


LIBMPI = _load()

# Handle and request types: int in MPICH, pointers in Open MPI.
HANDLE = types.int32 if MPI._sizeof(MPI.Comm) == 4 else types.intp
HANDLE_DTYPE = np.int32 if MPI._sizeof(MPI.Comm) == 4 else np.intp
REQUEST_DTYPE = np.int32 if MPI._sizeof(MPI.Request) == 4 else np.intp
STATUS_BYTES = 64            # >= sizeof(MPI_Status) in MPICH (20) and Open MPI (24)

_int = types.int32
_ptr = types.voidptr
isend = types.ExternalFunction("MPI_Isend", _int(_ptr, _int, HANDLE, _int, _int, HANDLE, _ptr))
irecv = types.ExternalFunction("MPI_Irecv", _int(_ptr, _int, HANDLE, _int, _int, HANDLE, _ptr))
waitall = types.ExternalFunction("MPI_Waitall", _int(_int, _ptr, _ptr))
testall = types.ExternalFunction("MPI_Testall", _int(_int, _ptr, _ptr, _ptr))
allreduce = types.ExternalFunction("MPI_Allreduce", _int(_ptr, _ptr, _int, HANDLE, HANDLE, HANDLE))
start = types.ExternalFunction("MPI_Start", _int(_ptr))
startall = types.ExternalFunction("MPI_Startall", _int(_int, _ptr))


# Slots of the handles array.
H_COMM, H_FLOAT, H_INT64, H_MAX = range(4)


def handles(comm, float_dtype) -> np.ndarray:
    """[H_COMM, H_FLOAT, H_INT64, H_MAX]: the communicator, the state's float datatype, MPI_INT64_T and
    MPI_MAX as the integers compiled code passes to MPI."""
    ftype = MPI.DOUBLE if np.dtype(float_dtype) == np.float64 else MPI.FLOAT
    # mpi4py gives MPICH's int handles as unsigned numbers: a communicator made by Split or Dup has the
    # top bit set (0x84000002), beyond int32.  The C int's bits are what MPI wants: wrap, do not refuse.
    raw = [MPI._handleof(comm), MPI._handleof(ftype), MPI._handleof(MPI.INT64_T), MPI._handleof(MPI.MAX)]
    return np.array([h % (1 << 64) for h in raw], np.uint64).astype(HANDLE_DTYPE)
