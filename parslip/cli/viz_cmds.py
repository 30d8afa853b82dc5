"""Subcommands that render run files: (none yet).

Each subcommand adds its parser in ``register`` and does its work in a
function that imports what it needs, so `parslip --help` stays fast.
"""


def register(sub) -> None:
    """Add this module's subcommands to the ``parslip`` parser."""
