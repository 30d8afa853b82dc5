"""What the ranks agree on between calls of the compiled loop: stop, checkpoint, how far to go next.

Responsible for the run's control protocol.  Between two calls of the loop
every rank calls ``agree`` at the same step (the calls are in lockstep: see
the rule in ``engine.loop``), and one MPI_Allreduce(MAX) of a few integers
makes every rank take the same branch:

  SIGNAL      1 after SIGINT (Ctrl-C), 2 after SIGTERM or SIGUSR1 (Slurm's warning signals), on any rank
  DEADLINE    1 when rank 0's clock passed --stop-after
  WALL        1 when rank 0's clock says a wall-clock checkpoint is due (checkpoint.wall)
  CHUNK       the steps of the next call, from rank 0's measured rate: about AGREE_S of work

Signals only raise a flag here (a second Ctrl-C interrupts at once); a rank
blocked in MPI cannot reach ``agree``, and then the monitor thread ends the
job (``engine.monitor``).  Checkpoints on a simulated-time cadence fall on
steps every rank computes alike (``next_stop``).
"""
from __future__ import annotations

import signal
import time

import numpy as np

from .. import hooks

CHECKPOINT, STOP, INTERRUPT = "checkpoint", "stop", "interrupt"
# Wall time between agreements of the ranks (and so progress, signals, deadlines), s.
AGREE_S = 0.5
# Slots of the agreed vector.
SIGNAL, DEADLINE, WALL, CHUNK = range(4)
AGREE_SIZE = 4


class RunControl:
    """The agreement of one run; ``agree`` is collective over ``comm``."""

    def __init__(self, comm, setup, *, stop_after: float | None = None, started: float | None = None,
                 monitor=None):
        self.comm = comm if comm is not None and comm.Get_size() > 1 else None
        self.rank = comm.Get_rank() if self.comm is not None else 0
        st = setup
        every = st.scene["checkpoint.every"]
        self.every = int(round(every * st.t_unit / st.dt)) if every else 0
        self.wall_every = st.scene["checkpoint.wall"]
        started = time.monotonic() if started is None else started
        self.deadline = started + stop_after if stop_after is not None else None
        self.last_ckpt = time.monotonic()
        self.monitor = monitor
        self.flag = 0                           # 1: SIGINT, 2: SIGTERM or SIGUSR1
        self.chunk = 0
        self.ckpt_step = -1                     # the step of the last checkpoint: never two at one step
        self._t = time.monotonic()
        self._n = None
        self._previous = {}
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1):
            try:
                self._previous[sig] = signal.signal(sig, self._on_signal)
            except ValueError:                  # not the main thread (a test harness): no signals then
                pass

    def _on_signal(self, signum, frame):
        if signum == signal.SIGINT:
            if self.flag == 1:                  # asked twice: stop now, whatever it costs
                raise KeyboardInterrupt
            self.flag = 1
        elif not self.flag:
            self.flag = 2

    def restore_signals(self):
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous = {}

    def next_stop(self, n: int) -> int:
        """The next step at which the loop must come back (a simulated-time checkpoint)."""
        if self.every:
            return (n // self.every + 1) * self.every
        return 1 << 62

    def _hooks(self, n: int):
        """Fault injection for the tests (``parslip.hooks``): a rank that fails, stops or blocks alone."""
        if hooks.at("raise_at", self.rank, n):
            raise RuntimeError(f"injected failure on rank {self.rank} at step {hooks.get('raise_at')[1]} "
                               f"({hooks.VARIABLE})")
        if hooks.at("stop_at", self.rank, n):
            import os
            os.kill(os.getpid(), signal.SIGSTOP)
        if hooks.at("block_at", self.rank, n):
            while True:                         # never reaches the collective the other ranks wait in
                time.sleep(1.0)

    def agree(self, sim):
        """(action or None, steps for the next call): the same on every rank."""
        n = sim.n
        if hooks.active():
            self._hooks(n)
        now = time.monotonic()
        mine = np.zeros(AGREE_SIZE, np.int64)
        mine[SIGNAL] = self.flag
        if self.rank == 0:
            if self.deadline is not None and now >= self.deadline:
                mine[DEADLINE] = 1
            if self._n is not None and n > self._n:
                rate = (n - self._n) / max(now - self._t, 1e-6)
                self.chunk = int(np.clip(rate * AGREE_S, 16, 1 << 22))
            self._t, self._n = now, n
            mine[WALL] = int(bool(self.wall_every and now - self.last_ckpt >= self.wall_every))
            mine[CHUNK] = self.chunk
        if self.monitor is not None:
            self.monitor.phase("agree")
        if self.comm is not None:
            agreed = np.zeros_like(mine)
            self.comm.Allreduce(mine, agreed, op=_max())
        else:
            agreed = mine
        if self.monitor is not None:
            self.monitor.agreed(n)
        self.chunk = int(agreed[CHUNK])
        steps = self.chunk or None
        if agreed[SIGNAL] or agreed[DEADLINE]:
            self.ckpt_step = n
            return (INTERRUPT if agreed[SIGNAL] == 1 else STOP), steps
        if n != self.ckpt_step and (agreed[WALL] or (self.every and n > 0 and n % self.every == 0
                                                     and n < sim.setup.n_steps)):
            self.last_ckpt = now
            self.ckpt_step = n
            return CHECKPOINT, steps
        return None, steps


def _max():
    from mpi4py import MPI
    return MPI.MAX
