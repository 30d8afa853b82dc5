"""Compiled kernels: numpy and numba only, no MPI, no files.

``stencil``   the bulk Born update of one row segment (one loop per row kind)
``interface`` break, re-form and forces of the interface bonds; frame records
``reference`` the plain per-node kernels of the first engine, kept as the
              independent implementation the fused loop is tested against
"""
