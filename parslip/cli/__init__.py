"""The ``parslip`` command line: subcommands, exit codes, logging and progress."""
from .main import main  # noqa: F401
