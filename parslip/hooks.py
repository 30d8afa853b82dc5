"""Fault injection for the test suite: the one test hook, read once at start-up.

Production code never reads an environment variable of its own to misbehave.
Tests that need a fault set ``PARSLIP_TEST_HOOKS`` (which ``mpiexec`` passes
to every rank) to ``;``-separated ``NAME=VALUE`` items; this module parses it
once, when it is first imported, and the code asks ``hooks.get(NAME)``:

  raise_at=RANK:STEP        that rank raises RuntimeError once the run reaches STEP (a rank that fails
                            alone: the job must come down, not hang)
  stop_at=RANK:STEP         that rank stops itself with SIGSTOP once the run reaches STEP (a rank that
                            stops answering: the watchdog must fire)
  block_at=RANK:STEP        that rank skips the agreement at STEP and waits in a lone barrier instead (a
                            rank that answers heartbeats but never reaches the collective the others are in)
  compile_error=RANK        that rank's first call of the compiled loop raises RuntimeError, as a compile that
                            failed would (every rank must end with the same error, none left waiting)
  kill_in_checkpoint=[RANK:]K  that rank (0 when not given) kills itself with SIGKILL halfway through writing
                            its share of the K-th checkpoint
  write_error_at_frame=K    writing interface frame K or later fails with ENOSPC (a full disk)
  hold_at_frame=K           rank 0, about to write interface frame K or later, creates OUT.held and waits
                            (up to 120 s) until the test removes it: a test can fill the disk mid-run
                            however fast the host runs
  hold_before_picture=1     rank 0 of `parslip run`, about to draw the space-time picture of a complete run,
                            creates PNG.held and waits (up to 120 s) until it is removed or a signal comes

For example ``PARSLIP_TEST_HOOKS="raise_at=1:300"``.  Unset, every hook is
None and costs nothing.  A malformed value is bad input (exit 2), named.
"""
from __future__ import annotations

import os

from .errors import ConfigError

VARIABLE = "PARSLIP_TEST_HOOKS"

# name: how its value is read
_PAIRS = ("raise_at", "stop_at", "block_at")
_INTS = ("compile_error", "write_error_at_frame", "hold_at_frame", "hold_before_picture")
_RANK_OPTIONAL = ("kill_in_checkpoint",)        # [RANK:]K, stored as (RANK, K)


def parse(text: str | None) -> dict:
    """``"raise_at=1:300;kill_in_checkpoint=2"`` -> {"raise_at": (1, 300), "kill_in_checkpoint": (0, 2)}."""
    out: dict = {}
    for item in (text or "").split(";"):
        item = item.strip()
        if not item:
            continue
        name, _, value = item.partition("=")
        name, value = name.strip(), value.strip()
        try:
            if name in _PAIRS + _RANK_OPTIONAL:
                given = value if ":" in value or name in _PAIRS else "0:" + value
                a, b = (int(v) for v in given.split(":"))
                if a < 0 or b < 0:
                    raise ValueError
                out[name] = (a, b)
            elif name in _INTS:
                k = int(value)
                if k < 0:
                    raise ValueError
                out[name] = k
            else:
                raise KeyError
        except KeyError:
            raise ConfigError(f"{VARIABLE}: {name!r} = {value!r}: unknown hook; accepted: "
                              f"{', '.join(_PAIRS + _INTS + _RANK_OPTIONAL)}") from None
        except ValueError:
            form = "RANK:STEP (two integers >= 0)" if name in _PAIRS else \
                "[RANK:]K (integers >= 0)" if name in _RANK_OPTIONAL else "an integer >= 0"
            raise ConfigError(f"{VARIABLE}: {name} = {value!r}: accepted: {form}") from None
    return out


_error: str | None = None
try:
    _HOOKS = parse(os.environ.get(VARIABLE))
except ConfigError as e:           # reported by ``check`` at the start of a run, not at import
    _HOOKS, _error = {}, str(e)


def check() -> None:
    """Raise the ConfigError of a malformed ``PARSLIP_TEST_HOOKS`` (called where a run starts)."""
    if _error:
        raise ConfigError(_error)


def get(name: str):
    """The hook's value, or None when it is not set."""
    return _HOOKS.get(name)


def at(name: str, rank: int, step: int) -> bool:
    """True when the RANK:STEP hook ``name`` is set for this rank and the run has reached its step."""
    v = _HOOKS.get(name)
    return v is not None and v[0] == rank and step >= v[1]


def hold(marker: str, limit_s: float = 120.0) -> None:
    """The hold of ``hold_at_frame`` and ``hold_before_picture``: create ``marker`` and wait until the test
    removes it (or ``limit_s`` passes, or a signal's handler raises)."""
    import time
    open(marker, "w").close()
    deadline = time.monotonic() + limit_s
    while os.path.exists(marker) and time.monotonic() < deadline:
        time.sleep(0.02)


def active() -> bool:
    return bool(_HOOKS)
