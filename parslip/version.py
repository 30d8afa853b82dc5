"""parslip's version and the commit it runs at: one definition, below every layer (provenance in every
output file, ``parslip --version``).  Standard library only, so ``parslip --version`` works where numpy,
h5py or MPI are missing."""
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


def describe() -> str:
    """``parslip --version``: the version and the commit of the checkout, "(modified)" when it has
    uncommitted changes to tracked files; outside a git checkout of parslip (an installed package) it says
    so instead of a commit."""
    commit = git_commit()
    if commit == "unknown":
        return f"parslip {__version__}, an installed package at {os.path.dirname(os.path.abspath(__file__))} " \
               "(not a git checkout: no commit to report)"
    rev, dirty = commit.removesuffix("-dirty"), commit.endswith("-dirty")
    return f"parslip {__version__}, commit {rev}" + (" (modified)" if dirty else "")
