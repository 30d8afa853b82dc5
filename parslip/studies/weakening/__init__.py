"""The studies of ruptures on the slip-weakening interface (docs/studies/weakening.md): Andrews' transition
distance against S, Kammer et al.'s supershear equation of motion on the same runs, and the cohesive zone's
contraction with speed (``cohesive_zone``, run by ``postprocess/weakening_cohesive_zone.py``).

Each study is a module of this package, ``parslip.studies.weakening.<study>``, with

    tabulate(runs: str, img: str, tables: str) -> str

which reads the sweeps it ran (``run/studies/weakening_<study>*.toml``, written under ``runs`` by ``parslip
sweep``), writes ``tables/weakening_<study>.csv`` (a row per run, with ``scene`` and ``commit`` columns) and
its figures under ``img``, and returns the Markdown the page quotes.  ``postprocess/weakening.py <study>``
runs it; ``bash postprocess/docs_numbers.sh weakening_andrews`` runs the sweeps and both studies.  Generic
measures (the rupture-time field, the daughter's birth, the law's scales) live in ``parslip.analysis``; only
what is particular to a study lives here.
"""
from __future__ import annotations

import glob
import importlib
import os

from ..cracks import points, provenance, write  # noqa: F401  (the sweeps' reader and the tables' writer)

STUDIES = ("andrews", "kammer", "shape")
# The sweeps each study reads: Kammer's speeds are measured on Andrews' runs.
SWEEPS = {"andrews": "andrews", "kammer": "andrews", "shape": "shape"}
# Study 5, precursors that are cracks (``precursors``): the loader study on the weakening interface.
STUDIES += ("precursors",)
SWEEPS["precursors"] = "precursors"


def sweeps(runs: str, study: str) -> list[str]:
    """The output directories of the study's sweeps under ``runs``, one per sweep file
    ``run/studies/weakening_<sweeps>*.toml`` (named as the file), sorted."""
    stem = SWEEPS[study]
    return sorted(d for d in glob.glob(os.path.join(runs, f"weakening_{stem}*"))
                  if os.path.isfile(os.path.join(d, "summary.csv")))


def tabulate(study: str, runs: str, img: str, tables: str) -> str:
    """Run study ``study``'s tabulation (see the module docstring); the PDFs its figures leave removed."""
    if study not in STUDIES:
        raise ValueError(f"study {study!r}: accepted: {', '.join(STUDIES)}")
    os.makedirs(img, exist_ok=True)
    os.makedirs(tables, exist_ok=True)
    md = importlib.import_module(f"parslip.studies.weakening.{study}").tabulate(runs, img, tables)
    # The page shows the PNGs; ``save`` also writes PDFs, which the docs do not keep.
    for f in glob.glob(os.path.join(img, f"weakening_{study}_*.pdf")):
        os.remove(f)
    return md
