"""What the command line adds to the time loop: an agreed stop on Ctrl-C (and SIGTERM/SIGUSR1), and a test fault.

Responsible for two things that ride on the progress callback, which the
time loop calls on every rank after every step:

- **Ctrl-C.**  SIGINT reaches the ranks at different moments (mpiexec forwards
  it, a terminal sends it to the whole process group), and Python raises
  KeyboardInterrupt wherever a rank happens to be, sometimes where it is
  swallowed (a weakref callback).  A rank that leaves the loop while another
  waits for its halo, or for its share of a collective HDF5 write, hangs the job
  and leaves an unreadable file.  So SIGINT only raises a flag; every
  ``every`` steps the ranks agree (one allreduce of an int) and all raise
  KeyboardInterrupt at the same step, and the writer's collective close then
  marks the file ``interrupted at step N``.  A second Ctrl-C interrupts at once.
  This relies on the time loop calling ``update(n)`` on every rank with the
  same n, as ``Simulation.run`` does (the Progress object prints on rank 0 only).
  SIGTERM (Slurm's at the time limit) and SIGUSR1 (which the batch scripts ask
  for before it) are treated alike while nothing else handles them.
- **A test fault.**  ``PARSLIP_TEST_FAIL=RANK:STEP`` raises RuntimeError on that
  rank alone when it reaches that step, so tests can check that one failing
  rank takes the whole job down (MPI_Abort) instead of leaving the others
  waiting.  Unset, it costs nothing.
"""
from __future__ import annotations

import os
import signal

from ..errors import ConfigError

FAULT_VAR = "PARSLIP_TEST_FAIL"


def parse_fault(value: str | None) -> tuple[int, int] | None:
    """``"1:300"`` -> (rank 1, step 300); None when unset."""
    if not value:
        return None
    try:
        rank, step = (int(v) for v in value.split(":"))
        if rank < 0 or step < 0:
            raise ValueError
    except ValueError:
        raise ConfigError(f"{FAULT_VAR}={value!r}: accepted: RANK:STEP with two integers >= 0, "
                          "e.g. 1:300 (raise on rank 1 at step 300)") from None
    return rank, step


class LoopHooks:
    """Wraps the progress object the time loop calls with ``update(n)`` on every rank."""

    def __init__(self, progress, comm, every: int, environ=None):
        self.progress = progress
        self.comm = comm
        self.every = max(1, int(every))
        self.rank = comm.Get_rank() if comm is not None else 0
        self.fault = parse_fault((os.environ if environ is None else environ).get(FAULT_VAR))
        self.interrupted = 0
        self._previous = {signal.SIGINT: signal.signal(signal.SIGINT, self._on_signal)}
        # Slurm's SIGTERM at the time limit and the SIGUSR1 the batch scripts ask for
        # would otherwise kill the ranks mid-write; whoever handles them already keeps them.
        for sig in (signal.SIGTERM, signal.SIGUSR1):
            if signal.getsignal(sig) == signal.SIG_DFL:
                self._previous[sig] = signal.signal(sig, self._on_signal)

    def _on_signal(self, signum, frame):
        if self.interrupted:             # asked twice: stop now, whatever it costs
            raise KeyboardInterrupt
        self.interrupted = 1

    def update(self, n: int, *args, **kwargs):
        self.progress.update(n, *args, **kwargs)
        if self.fault and self.fault == (self.rank, n):
            raise RuntimeError(f"injected failure on rank {self.rank} at step {n} ({FAULT_VAR})")
        if n % self.every == 0:
            stop = self.interrupted
            if self.comm is not None and self.comm.Get_size() > 1:
                stop = self.comm.allreduce(stop)
            if stop:
                raise KeyboardInterrupt

    def done(self):
        """After the loop: the signals get their previous handlers back."""
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self.progress.done()

    def __getattr__(self, name):         # done(), phase(), ... of the wrapped progress
        return getattr(self.progress, name)


def hook_loop(progress, comm, setup) -> LoopHooks:
    """The wrapper ``cmd_run`` hands to the time loop; agrees on a stop every frame or 200 steps."""
    return LoopHooks(progress, comm, min(setup.frame_every, 200))
