"""parslip: onset of frictional slip at adhesive elastic interfaces, on a distributed Born lattice."""
__version__ = "0.1.0"
