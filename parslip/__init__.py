"""parslip: onset of frictional slip at adhesive elastic interfaces, on a distributed Born lattice.

The public facade, above every layer of the package:

    import parslip
    run = parslip.run("run/push.toml", out="out/push.vtkhdf")      # a run, as `parslip run` makes it
    run = parslip.open("out/push.vtkhdf")                            # a finished (or partial) run file
    run.interface["ux"], run.times, run.fronts(), run.mu, run.mu_s, run.precursors()

``import parslip`` loads neither numpy nor h5py nor MPI: each name is imported on first use.
"""
from .version import __version__  # noqa: E402,F401

__all__ = ["run", "open", "Run", "ConfigError", "RunError", "__version__"]


def run(scene, *, out, sets=None, restart=None, overwrite=False, comm=None, progress=True, stop_after=None,
        watchdog=None):
    """Run a scene and return its results, the object ``parslip.open(out)`` returns.

    Units are those of the scene keys (``parslip keys``).  The datasets written are those of ``parslip run``,
    bit for bit.

    Args:
        scene: a TOML scene file path, or a mapping of scene keys (flat ``{"drive.v0": 1e-3}`` or nested).
        out: the output file (.vtkhdf); it must not exist unless ``overwrite`` or ``restart``.
        sets: overrides: ``{"drive.v0": 1e-2}`` or ``["drive.v0=1e-2"]`` (TOML literals, as ``--set``).
        restart: None; a checkpoint path (``OUT.ckpt.h5``) to continue from; or "auto" (continue when a
            checkpoint exists and the run is not complete, do nothing when it is complete).
        overwrite: replace an existing output file.
        comm: an mpi4py communicator to run on (every rank of it calls ``run``); None: this process
            alone, and no MPI library is loaded.
        progress: log progress lines on rank 0 (logger "parslip"; lines carry rank/size).
        stop_after: wall-clock seconds after which the run writes a checkpoint and stops.
        watchdog: seconds without an agreement of the ranks before the job is aborted (default: the
            scene's run.watchdog, 180 s; 0 = off).

    Returns:
        Run: ``parslip.analysis.results.Run`` with ``.outcome`` (``engine.runner.Outcome``): its ``status``
            is "complete", "checkpointed at step N" (SIGTERM/SIGUSR1 or stop_after) or "interrupted at
            step N" (Ctrl-C); a checkpoint continues either.

    Raises:
        ConfigError: bad input (a key, a value, a path: the message names it and what is accepted; the
            command line exits 2), on every rank alike.
        RunError: a run that failed on the way (non-finite state, slip beyond the halo, a failed write: the
            message gives the step and place; the command line exits 3), on every rank alike.
    """
    from .analysis.results import Run
    from .engine.runner import run_scene
    outcome = run_scene(scene, out=out, sets=sets, restart=restart, overwrite=overwrite, comm=comm,
                        progress=progress, stop_after=stop_after, watchdog=watchdog,
                        command="parslip.run (Python)")
    result = Run(outcome.out)
    result.outcome = outcome
    return result


def __getattr__(name):
    # Lazy exports: the CLI and MPI ranks import parslip without paying for h5py/numpy here.
    if name in ("open", "Run"):
        from .analysis import results
        return getattr(results, name)
    if name in ("ConfigError", "RunError"):
        from . import errors
        return getattr(errors, name)
    raise AttributeError(f"module 'parslip' has no attribute {name!r}")
