"""Marking an output file failed after the job that wrote it was aborted.

Responsible for the status line of a run file when no rank of the run can
set it any more: the collective (mpio) writer holds the file on every rank,
and a rank that is not rank 0 never holds it.  Before an abort such a rank
starts this module as a detached process (``mark_failed_later``); it waits
until the file can be opened for writing (the aborted ranks held it open and
locked), then sets ``status`` to "failed: REASON" if the file still says
"running", and exits.  It gives up quietly after ``WAIT_S``: a status line
is worth a try, never a hang.

    python -m parslip.io.postmortem FILE REASON [WAIT_S]
"""
from __future__ import annotations

import os
import subprocess
import sys
import time

WAIT_S = 120.0
FIRST_TRY_S = 1.0          # the aborted ranks need a moment to die and release the file


def mark_failed_later(path: str, reason: str, wait_s: float = WAIT_S) -> None:
    """Start the detached marker (it outlives this process and its MPI job)."""
    subprocess.Popen([sys.executable, "-m", "parslip.io.postmortem", os.path.abspath(path), reason, str(wait_s)],
                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                     start_new_session=True, close_fds=True)


def mark_failed(path: str, reason: str, wait_s: float = WAIT_S) -> bool:
    """Set status "failed: REASON" once the file can be opened for writing; True when it was set."""
    import h5py

    from .contract import put_status, read_status
    deadline = time.monotonic() + wait_s
    time.sleep(FIRST_TRY_S)
    while True:
        try:
            with h5py.File(path, "r+") as f:
                if read_status(f) == "running":
                    put_status(f, f"failed: {reason}")
                return True
        except (OSError, KeyError):
            if time.monotonic() > deadline:
                return False
            time.sleep(0.5)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    path, reason = argv[0], argv[1]
    wait_s = float(argv[2]) if len(argv) > 2 else WAIT_S
    return 0 if mark_failed(path, reason, wait_s) else 1


if __name__ == "__main__":
    sys.exit(main())
