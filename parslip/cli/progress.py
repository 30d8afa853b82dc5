"""Rank-aware logging and the progress line of long runs.

Log lines carry rank/size; ranks other than 0 log at WARNING only, so a
run on many ranks prints one voice.  Rank 0 shows progress: simulated time
in l/c_r, steps/s and the ETA; on a TTY as one refreshed line, otherwise as
periodic log lines (batch jobs).
"""
from __future__ import annotations

import logging
import sys
import time


def setup_logging(rank: int, size: int, level=logging.INFO) -> logging.Logger:
    log = logging.getLogger("parslip")
    log.handlers.clear()
    h = logging.StreamHandler(sys.stderr)
    h.setFormatter(logging.Formatter(f"%(asctime)s parslip {rank}/{size} %(levelname)s: %(message)s",
                                     "%H:%M:%S"))
    log.addHandler(h)
    log.setLevel(level if rank == 0 else logging.WARNING)
    log.propagate = False
    return log


def _hms(s: float) -> str:
    s = int(max(s, 0))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class Progress:
    """Called every step with the step index; prints every ``every_s`` seconds."""

    def __init__(self, setup, every_s: float = 10.0, enabled: bool = True, stream=None):
        self.st = setup
        self.every = every_s
        self.enabled = enabled
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.t0 = self.last = time.monotonic()
        self.n0 = None
        self.log = logging.getLogger("parslip")

    def phase(self, n: int) -> str:
        st = self.st
        if n < st.n_ramp:
            return "ramp"
        return "settle" if n < st.n_drive_start else "drive"

    def update(self, n: int, force: bool = False):
        if not self.enabled:
            return
        now = time.monotonic()
        if self.n0 is None:
            self.n0, self.t0 = n, now
            return
        if not force and now - self.last < self.every:
            return
        self.last = now
        st = self.st
        rate = (n - self.n0) / max(now - self.t0, 1e-9)
        eta = (st.n_steps - n) / rate if rate > 0 else float("inf")
        t = st.to_lcr((n - st.n_drive_start) * st.dt)
        msg = (f"step {n}/{st.n_steps} ({self.phase(n)}), t = {t:.2f}/{st.to_lcr(st.n_drive * st.dt):.1f} l/c_r, "
               f"{rate:,.0f} steps/s, ETA {_hms(eta)}")
        if self.tty:
            self.stream.write("\r" + msg + "  ")
            self.stream.flush()
        else:
            self.log.info(msg)

    def done(self):
        if self.enabled and self.tty:
            self.stream.write("\n")
