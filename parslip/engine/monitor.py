"""The monitor thread of a run: progress, the compile notice, signals while blocked, and the watchdog.

Responsible for everything a run must say or do while its main thread cannot:
the compiled loop runs without the GIL (``loop.advance``), and a rank waiting
in MPI runs no Python at all.  The thread wakes every ``TICK_S`` and

- prints the progress line on rank 0 (``progress.Progress``), from the step
  the loop publishes in ``diag.beat``, however long a compiled call runs;
- says so when the loop is being compiled (the first run of a machine);
- exchanges heartbeats (``parallel.heartbeat``) so that rank 0 knows where
  every rank is and which one stopped answering;
- fires the watchdog when the ranks have not agreed (``agreed``, called by
  the main thread after each agreement) for longer than ``watchdog_s``:
  every rank that can still speak logs its step and phase, the output file
  is marked failed (``on_fail``), one line names the rank that stopped
  answering, and MPI_Abort ends the job with exit code 3;
- ends the job within seconds when SIGTERM, SIGUSR1 or SIGINT arrived while
  this rank is blocked (no agreement since the signal for ``signal_grace``
  seconds): a checkpoint needs every rank, so none can be written then.

Signals reach this thread through ``signal.set_wakeup_fd``: Python's own
handlers run only in the main thread, which may be waiting in MPI.
"""
from __future__ import annotations

import logging
import os
import signal
import socket
import sys
import threading
import time

from . import loop as L

PHASES = ("start", "restore", "compile", "loop", "agree", "write frames", "snapshot", "checkpoint", "finish")
TICK_S = 0.25
COMPILE_NOTICE_S = 2.0          # say "compiling" when the first call has taken this long
# A cold compile of the time loop, as measured (docs/developer/kernels.md, "What a compile costs"): CPU time on the
# one rank per kernel cache that compiles (``engine.compile``); its wall time is longer on a busy machine.
COMPILE_CPU_S = 40
SIGNAL_GRACE_S = 5.0            # a signal not acted on by an agreement within this long (or twice the
                                # longest gap between agreements) ends the job
HEARTBEAT_S = 2.0               # at most; a tenth of the watchdog limit when that is shorter
SIGNAL_NAMES = {signal.SIGINT: "SIGINT", signal.SIGTERM: "SIGTERM", signal.SIGUSR1: "SIGUSR1"}
EXIT_ABORT = 3


class Monitor:
    """One rank's monitor thread; ``start`` and ``stop`` from the main thread."""

    def __init__(self, sim, comm=None, *, progress=None, watchdog_s: float = 0.0, on_fail=None, log=None):
        self.sim = sim
        self.comm = comm if comm is not None and comm.Get_size() > 1 else None
        self.rank, self.size = sim.rank, sim.size
        self.progress = progress
        self.watchdog_s = float(watchdog_s or 0.0)
        self.on_fail = on_fail
        self.log = log or logging.getLogger("parslip")
        self.hb = None
        if self.comm is not None:
            from ..parallel import heartbeat
            if heartbeat.available(self.comm):
                self.hb = heartbeat.for_comm(self.comm)          # collective the first time
            elif self.watchdog_s and self.rank == 0:
                self.log.warning("watchdog: MPI without MPI_THREAD_MULTIPLE, so no heartbeats: a hang is still "
                                 "caught, but the rank that stopped answering cannot be named")
        self.hb_every = min(HEARTBEAT_S, self.watchdog_s / 10) if self.watchdog_s else HEARTBEAT_S
        self._phase, self._since = "start", time.monotonic()
        self.agreements = 0
        self.last_agree = None           # armed after the first agreement that follows compilation
        self.max_gap = 0.0
        self.signal_at = self.signum = None
        self.fired = False
        self._compile_said = 0.0
        self._last_beat = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="parslip-monitor", daemon=True)
        self._wake_r = self._wake_w = None
        self._old_wakeup = None

    # ------------------------------------------------------------- main thread --
    def start(self):
        if threading.current_thread() is threading.main_thread():
            self._wake_r, self._wake_w = socket.socketpair()
            for s in (self._wake_r, self._wake_w):
                s.setblocking(False)
            try:
                self._old_wakeup = signal.set_wakeup_fd(self._wake_w.fileno(), warn_on_full_buffer=False)
            except ValueError:
                self._old_wakeup = None
        self._thread.start()
        return self

    def stop(self):
        self._stop.set()
        self._thread.join(timeout=5)
        if self._wake_w is not None:
            try:
                signal.set_wakeup_fd(self._old_wakeup if self._old_wakeup is not None else -1)
            except ValueError:
                pass
            self._wake_r.close()
            self._wake_w.close()
            self._wake_w = None

    def phase(self, name: str):
        """The main thread enters ``name`` (one of PHASES)."""
        self._phase, self._since = name, time.monotonic()

    def compiled(self, n: int):
        """The first call of the loop returned: progress rates count from here."""
        if self.progress is not None:
            self.progress.start(n)

    def agreed(self, n: int):
        """Every rank took part in an agreement at step ``n`` (a signal before it is now acted on)."""
        now = time.monotonic()
        if self.last_agree is not None:
            self.max_gap = max(self.max_gap, now - self.last_agree)
        self.last_agree = now
        self.agreements += 1
        self.signal_at = None

    # ------------------------------------------------------------ the thread --
    def _step(self) -> int:
        beat = self.sim.diag.beat
        return int(beat[L.BEAT_STEP]) if beat[L.BEAT_IN_LOOP] else int(self.sim.n)

    def _beat(self) -> dict:
        return {"rank": self.rank, "step": self._step(), "phase": PHASES.index(self._phase),
                "agreements": self.agreements, "in_loop": int(self.sim.diag.beat[L.BEAT_IN_LOOP])}

    def _run(self):
        while not self._stop.wait(TICK_S):
            if self.fired:
                continue
            try:
                now = time.monotonic()
                self._signals(now)
                if self.hb is not None:
                    self._heartbeats(now)
                self._speak(now)
                self._watch(now)
            except Exception as e:           # the monitor must never take a healthy run down
                self.log.warning(f"monitor: {e.__class__.__name__}: {e}")

    def _signals(self, now):
        if self._wake_r is None:
            return
        try:
            data = self._wake_r.recv(64)
        except (BlockingIOError, OSError):
            return
        for b in data:
            if b in SIGNAL_NAMES and self.signal_at is None:
                self.signal_at, self.signum = now, b

    def _heartbeats(self, now):
        from ..parallel.heartbeat import REPORT
        if now - self._last_beat >= self.hb_every:
            self._last_beat = now
            self.hb.send(self._beat())
        for src, tag, _ in self.hb.poll():
            if tag == REPORT and self.rank != 0:
                self._report_self(now)

    def _speak(self, now):
        p = self.progress
        if self._phase == "compile":
            took = now - self._since
            if took >= COMPILE_NOTICE_S and not self._compile_said:
                self._compile_said = now
                if self.rank == 0:
                    wait = " on one rank, the others wait" if self.size > 1 else ""
                    self.log.info(f"compiling the time loop for this machine (about {COMPILE_CPU_S} s of CPU{wait}; "
                                  f"once: later runs load it from numba's cache)")
            elif self._compile_said and p is not None and not p.tty and now - self._compile_said >= 30:
                self._compile_said = now
                self.log.info(f"still compiling the time loop ({took:.0f} s so far)")
            return
        if p is not None and p.t0 is not None and p.due(now):
            p.show(self._step(), now)

    def _watch(self, now):
        if self.comm is None:
            return
        if self.signal_at is not None and self._phase != "compile":
            grace = max(SIGNAL_GRACE_S, 2 * self.max_gap)
            if self.watchdog_s:
                grace = min(grace, self.watchdog_s)
            if self.rank != 0 and self.hb is not None and now - self.hb.heard[0][0] < grace:
                grace += 2.0                    # rank 0 still answers: let it speak for the job
            if now - self.signal_at > grace:
                name = SIGNAL_NAMES.get(self.signum, f"signal {self.signum}")
                self._report_self(now)
                who = ""
                if self.rank == 0 and self.hb is not None:
                    silent = self.hb.silent(max(grace, 3 * self.hb_every))
                    if silent:
                        who = "; " + ", ".join(f"rank {r}" for r in silent) + " stopped answering"
                self._abort(f"{name} arrived while rank {self.rank} was blocked at step {self._step()} in "
                            f"'{self._phase}' and the ranks did not meet for {now - self.signal_at:.0f} s{who}; a "
                            f"checkpoint needs every rank, so none was written")
                return
        if not self.watchdog_s or self.last_agree is None:
            return
        silence = now - self.last_agree
        if silence <= self.watchdog_s:
            return
        if self.rank == 0:
            self._fire_root(now, silence)
        elif self.hb is None:
            self._report_self(now)
            self._abort(self._reason(silence, f"this rank (rank {self.rank}) waits at step {self._step()} in "
                                              f"'{self._phase}'; heartbeats unavailable, so the rank that stopped "
                                              f"answering cannot be named"))
        else:
            t0, _ = self.hb.heard.get(0, (now, None))
            if now - t0 > max(self.watchdog_s / 2, 5 * self.hb_every) or silence > 1.5 * self.watchdog_s:
                self._report_self(now)
                self._abort(self._reason(silence, f"rank 0 stopped answering (silent for {now - t0:.0f} s)"))

    def _reason(self, silence, who) -> str:
        return (f"watchdog: the ranks have not agreed for {silence:.0f} s (limit {self.watchdog_s:g} s, "
                f"--watchdog or run.watchdog); {who}")

    def _fire_root(self, now, silence):
        from ..parallel.heartbeat import REPORT
        quiet = min(max(5 * self.hb_every, 3.0), self.watchdog_s / 2)      # silent: no beat for this long
        if self.hb is not None:
            self.hb.send(self._beat(), tag=REPORT)         # every rank that can still speak logs its state
        self._report_self(now)
        if self.hb is None:
            self._abort(self._reason(silence, f"rank 0 waits at step {self._step()} in '{self._phase}'; heartbeats "
                                              f"unavailable, so the rank that stopped answering cannot be named"))
            return
        time.sleep(1.0)                                      # let their lines out before the abort
        self.hb.poll()
        silent = self.hb.silent(quiet)
        if silent:
            parts = []
            for r in silent:
                t, b = self.hb.heard[r]
                where = f"; last heard at step {b['step']} in '{PHASES[b['phase']]}'" if b else ""
                parts.append(f"rank {r} stopped answering (silent for {now - t:.0f} s{where})")
            who = "; ".join(parts)
        else:
            places = {}
            mine = self._beat()
            for r, b in [(0, mine)] + [(r, b) for r, (_, b) in sorted(self.hb.heard.items()) if b]:
                places.setdefault((PHASES[b["phase"]], b["step"]), []).append(r)
            where = "; ".join(f"rank{'s' if len(rs) > 1 else ''} {', '.join(map(str, rs))} in '{ph}' at step {st}"
                              for (ph, st), rs in sorted(places.items(), key=lambda kv: kv[1]))
            who = f"no rank is silent, but they wait in different places: {where}"
        self._abort(self._reason(silence, who))

    def _report_self(self, now):
        last = f"{now - self.last_agree:.0f} s ago" if self.last_agree is not None else "never"
        self.log.error(f"watchdog report: rank {self.rank} is at step {self._step()} in '{self._phase}' "
                       f"({'inside' if self.sim.diag.beat[L.BEAT_IN_LOOP] else 'outside'} the compiled loop); "
                       f"last agreement of the ranks {last}")
        for h in self.log.handlers:
            h.flush()

    def _abort(self, reason: str):
        """Mark the output failed, print the one line, and end every rank with exit code 3."""
        self.fired = True
        note = ""
        if self.on_fail is not None:
            try:
                note = self.on_fail(reason) or ""
            except Exception as e:                           # noqa: BLE001 - the abort must happen
                note = f"the output file could not be marked failed ({e})"
        print(f"parslip {self.rank}/{self.size} ERROR: run failed: {reason}" + (f"; {note}" if note else "")
              + f"; MPI_Abort({EXIT_ABORT}) ends every rank", file=sys.stderr)
        sys.stderr.flush()
        time.sleep(0.5)
        try:
            self.comm.Abort(EXIT_ABORT)
        finally:
            os._exit(EXIT_ABORT)
