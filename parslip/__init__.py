"""parslip: onset of frictional slip at adhesive elastic interfaces, on a distributed Born lattice.

``parslip.open(path)`` returns a read-only result object (``analysis.results.Run``);
it is imported on first use so that ``import parslip`` loads neither numpy nor h5py.
"""
__version__ = "0.1.0"


def __getattr__(name):
    # Lazy export: the CLI and MPI ranks import parslip without paying for h5py/numpy here.
    if name in ("open", "Run"):
        from .analysis import results
        return getattr(results, name)
    raise AttributeError(f"module 'parslip' has no attribute {name!r}")
