"""The monitor thread in one process: progress while the main thread is busy elsewhere, the notice when
the loop compiles, an ETA that never counts compilation, and batch progress at least every 30 s."""
import io
import logging
import time
from types import SimpleNamespace

import numpy as np

from parslip.engine import loop as L
from parslip.engine.monitor import Monitor
from parslip.engine.progress import BATCH_MAX_S, Progress


class Setup:
    """What Progress reads of a Setup: 1000 steps, the drive from step 100, dt = 0.1, l/c_r = 10."""
    n_steps, n_ramp, n_drive_start, n_drive, dt = 1000, 50, 100, 900, 0.1

    def to_lcr(self, t):
        return t / 10.0


def fake_sim():
    return SimpleNamespace(rank=0, size=1, n=0, diag=SimpleNamespace(beat=np.zeros(L.BEAT_SIZE, np.int64)))


def logger():
    stream = io.StringIO()
    log = logging.getLogger("parslip.test_monitor")
    log.handlers[:] = [logging.StreamHandler(stream)]
    log.setLevel(logging.INFO)
    log.propagate = False
    return log, stream


def test_batch_progress_is_at_least_every_30_s_and_a_tty_refreshes_every_second():
    assert Progress(Setup(), every_s=600.0, stream=io.StringIO()).every == BATCH_MAX_S == 30.0

    class Tty(io.StringIO):
        def isatty(self):
            return True
    assert Progress(Setup(), every_s=600.0, stream=Tty()).every == 1.0


def test_eta_only_from_a_rate_measured_after_compilation():
    p = Progress(Setup(), every_s=1.0, stream=io.StringIO())
    assert "ETA" not in p.line(500, time.monotonic())                 # compiling: no rate yet
    p.start(200)
    now = p.t0 + 2.0
    line = p.line(400, now)                                           # 200 steps in 2 s: 100 steps/s
    assert "100 steps/s" in line and "ETA 0:00:06" in line            # (1000 - 400) / 100 s
    assert "ETA" not in p.line(201, p.t0 + 0.5)                       # measured over less than a second


def test_the_monitor_speaks_while_the_main_thread_does_not():
    """The main thread "compiles" for 2.5 s, then "runs" the loop (the beat advances) while it never calls
    the monitor: the compile notice appears once, then progress lines from the beat, with an ETA."""
    log, stream = logger()
    sim = fake_sim()
    prog = Progress(Setup(), every_s=0.3, stream=io.StringIO())
    prog.log = log
    mon = Monitor(sim, None, progress=prog, watchdog_s=0, log=log).start()
    try:
        mon.phase("compile")
        time.sleep(2.6)
        mon.compiled(0)
        mon.phase("loop")
        sim.diag.beat[L.BEAT_IN_LOOP] = 1
        for k in range(1, 31):
            sim.diag.beat[L.BEAT_STEP] = 10 * k
            time.sleep(0.05)
    finally:
        mon.stop()
    text = stream.getvalue()
    assert text.count("compiling the time loop") == 1, text
    lines = [ln for ln in text.splitlines() if ln.startswith("step ")]
    assert len(lines) >= 3, text
    assert "ETA" in lines[-1] and "(drive)" in lines[-1], lines
    steps = [int(ln.split()[1].split("/")[0]) for ln in lines]
    assert steps == sorted(steps) and steps[-1] > steps[0]


def test_a_quick_first_call_says_nothing_about_compiling():
    log, stream = logger()
    mon = Monitor(fake_sim(), None, progress=None, watchdog_s=0, log=log).start()
    try:
        mon.phase("compile")
        time.sleep(0.5)
        mon.phase("loop")
        time.sleep(0.5)
    finally:
        mon.stop()
    assert "compiling" not in stream.getvalue()
