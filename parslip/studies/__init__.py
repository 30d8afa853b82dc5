"""Studies: everything that starts many runs and gathers what they measured.

The layer above ``analysis`` and below ``cli``: a study calls the engine
(``engine.runner.run_scene``, the run as a library call) once per point and
reads each finished run back through ``analysis`` (``parslip.open``, the
friction observables).  ``analysis`` never starts a run; anything that does
belongs here.

  sweep.py        `parslip sweep SWEEP.toml -o OUTDIR`: a grid or list over scene keys run as one MPI
                  job split into groups of ranks (or as a Slurm job array), resumable, one output file
                  per point and a summary table (``analysis.table``)
  sweep_bench.py  `parslip bench --sweep`: the throughput of a sweep of small scenes on 1 and 2 ranks
"""
