"""Rank-aware logging and the progress line of a run.

Log lines carry rank/size; ranks other than 0 log at WARNING only, so a run
on many ranks speaks with one voice.  Rank 0 shows progress: the phase,
simulated time in l/c_r, steps/s and the ETA; on a terminal as one refreshed
line, otherwise (batch jobs) as log lines at least every ``BATCH_MAX_S``.
The rate, and so the ETA, is measured from the first step after the loop
was compiled or loaded: start-up and compilation never enter an ETA.
"""
from __future__ import annotations

import logging
import sys
import time

# Without a terminal a progress line appears at least this often (s), whatever output.progress_s says.
BATCH_MAX_S = 30.0
# On a terminal the line is refreshed this often at most (s).
TTY_S = 1.0
# The ETA is shown once the rate has been measured over this much wall time (s).
ETA_AFTER_S = 1.0


def setup_logging(rank: int, size: int, level=logging.INFO, stream=None) -> logging.Logger:
    """The ``parslip`` logger: one stderr handler whose lines carry rank/size."""
    log = logging.getLogger("parslip")
    log.handlers.clear()
    h = logging.StreamHandler(stream or sys.stderr)
    h.setFormatter(logging.Formatter(f"%(asctime)s parslip {rank}/{size} %(levelname)s: %(message)s",
                                     "%H:%M:%S"))
    log.addHandler(h)
    log.setLevel(level if rank == 0 else logging.WARNING)
    log.propagate = False
    return log


def hms(s: float) -> str:
    s = int(max(s, 0))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class Progress:
    """What rank 0 prints about a run's progress; the monitor thread calls ``due`` and ``line``."""

    def __init__(self, setup, every_s: float = 10.0, stream=None):
        self.st = setup
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every = min(every_s, TTY_S) if self.tty else min(every_s, BATCH_MAX_S)
        self.t0 = self.n0 = None
        self.last = time.monotonic()
        self.log = logging.getLogger("parslip")

    def start(self, n: int):
        """The loop is compiled and about to step from ``n``: the rate is measured from here."""
        self.t0, self.n0 = time.monotonic(), n

    def phase(self, n: int) -> str:
        st = self.st
        if n < st.n_ramp:
            return "ramp"
        return "settle" if n < st.n_drive_start else "drive"

    def due(self, now: float) -> bool:
        return now - self.last >= self.every

    def line(self, n: int, now: float) -> str:
        """The progress line at step n; the ETA only once a rate was measured after compilation."""
        st = self.st
        t = st.to_lcr((n - st.n_drive_start) * st.dt)
        msg = f"step {n}/{st.n_steps} ({self.phase(n)}), t = {t:.2f}/{st.to_lcr(st.n_drive * st.dt):.1f} l/c_r"
        if self.t0 is not None and now - self.t0 >= ETA_AFTER_S and n > self.n0:
            rate = (n - self.n0) / (now - self.t0)
            msg += f", {rate:,.0f} steps/s, ETA {hms((st.n_steps - n) / rate)}"
        return msg

    def show(self, n: int, now: float | None = None):
        now = time.monotonic() if now is None else now
        self.last = now
        msg = self.line(n, now)
        if self.tty:
            self.stream.write("\r" + msg + "  ")
            self.stream.flush()
        else:
            self.log.info(msg)

    def done(self):
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()
