"""The start-up line that says how the output file is written.

Responsible for naming the writer in the run's log, so a cluster user sees at
once whether the collective path is in use (``hdf5_mode`` in the file's root
attributes says the same afterwards).
"""
from __future__ import annotations

WRITERS = {
    "mpio": "writer: mpio (collective HDF5)",
    "gather": "writer: gather (rank 0 writes; h5py without MPI)",
}


def writer_line(mode: str) -> str:
    """One log line for the writer ``mode`` of ``io.output.Output``."""
    return WRITERS.get(mode, f"writer: {mode}")
