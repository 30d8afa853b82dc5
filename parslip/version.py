"""parslip's version and the commit of its checkout: one definition each, below every layer (provenance in
every output file and sweep record)."""
from __future__ import annotations

import os
import subprocess

__version__ = "0.1.0"


def git_commit() -> str:
    """The commit of the parslip checkout, with '-dirty' for local changes; 'unknown' outside git."""
    here = os.path.dirname(os.path.abspath(__file__))          # the package folder
    try:
        top = subprocess.run(["git", "rev-parse", "--show-toplevel"], cwd=here, capture_output=True, text=True,
                             timeout=5).stdout.strip()
        # Only parslip's own checkout counts, not a repository it happens to be installed inside.
        if not top or not os.path.samefile(os.path.join(top, "parslip"), here):
            return "unknown"
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True,
                             timeout=5).stdout.strip()
        if not rev:
            return "unknown"
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return rev + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError, ValueError):
        return "unknown"
