"""The errors a run can end with, each carrying its exit code.

The command line maps them to exit codes in one place (``cli.main``):
bad input exits 2 with one line naming the key, the value and what is
accepted; a run that failed on the way exits 3 with the step and the place.
"""
from __future__ import annotations

EXIT_BAD_INPUT = 2
EXIT_RUN_FAILED = 3


class ConfigError(ValueError):
    """Bad input (scene, override, output path, rank count, checkpoint): the message is the one line the user sees."""

    exit_code = EXIT_BAD_INPUT


class RunError(RuntimeError):
    """A run that failed on the way; the message says the step, the place and the likely cause."""

    exit_code = EXIT_RUN_FAILED


class NonFiniteError(RunError):
    """The state stopped being finite, or grew without bound."""


class SlipReachError(RunError):
    """The interface slid further than the MPI halo reaches."""


class WriteError(RunError):
    """A write of the output failed (no space, a quota, a folder that vanished), on some rank."""

    def __init__(self, message: str, path: str = "", frames_safe: int = 0):
        super().__init__(message)
        self.path, self.frames_safe = path, frames_safe


class OptionalPartMissing(ConfigError):
    """A command needs an optional extra that is not installed: the message names the extra (exit 2)."""


# Optional modules and the extra of pyproject.toml that installs each.
EXTRAS = {"pyvista": "viz", "imageio": "viz", "imageio_ffmpeg": "viz", "mkdocs": "docs", "pandas": "sweep",
          "xarray": "sweep", "h5netcdf": "sweep"}


def optional(module: str, purpose: str):
    """Import an optional module, or raise ``OptionalPartMissing`` naming the extra that installs it:
    ``optional("pyvista", "parslip render")``."""
    import importlib
    try:
        return importlib.import_module(module)
    except ImportError:
        extra = EXTRAS.get(module, module)
        raise OptionalPartMissing(f"{purpose} needs {module}, which is not installed; accepted: install the "
                                  f"[{extra}] extra (python -m pip install -e \".[{extra}]\")") from None
