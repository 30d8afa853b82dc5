"""Files: the output contract, the HDF5/VTKHDF writer and its provenance."""
