"""Studies: what runs many runs and reads them back: benchmarks, the accuracy study, the paper's
reproduction, sweeps.  The layer above ``analysis`` (which only reads run files) and below ``cli``.
"""
