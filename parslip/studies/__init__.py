"""Studies: what runs many runs and reads them back, the layer above ``analysis`` and below ``cli``.

Unlike ``parslip.analysis``, which only reads run files, a study starts runs (through one runner function
per study) and may import analysis, scene, io, the engine and the run API: the benchmarks and scaling
model (``bench``), the accuracy study, the paper's reproduction, sweeps.
"""
