"""The interface studies at a resolved scale (docs/studies/cracks.md): fracture energy against front speed,
precursors longer than their process zone, the supershear transition against Andrews' S, healing with
contact.

Each study is a module of this package, ``parslip.studies.cracks.<study>``, with

    tabulate(runs: str, img: str, tables: str) -> str

which reads the sweeps it ran (``run/studies/cracks_<study>*.toml``, written under ``runs`` by
``parslip sweep``), writes ``tables/cracks_<study>.csv`` (a row per front or per run, with ``scene`` and
``commit`` columns) and its figures under ``img``, and returns the Markdown the page quotes.
``postprocess/cracks.py <study>`` runs it; ``bash postprocess/docs_numbers.sh cracks_<study>`` runs the
sweeps and then it.  Generic measures (G, Gamma, S, a front's band, the process zone) live in
``parslip.analysis``; only what is particular to a study lives here.
"""
from __future__ import annotations

import glob
import importlib
import os

from parslip.analysis import table
from parslip.analysis.results import Run

STUDIES = ("energy", "precursors", "supershear", "healing")
# The studies whose tables can be fitted again without their runs (``refit(tables, img)`` in their module).
REFIT = ("precursors",)


def sweeps(runs: str, study: str) -> list[str]:
    """The output directories of the study's sweeps under ``runs``, one per sweep file
    ``run/studies/cracks_<study>*.toml`` (named as the file), sorted."""
    return sorted(d for d in glob.glob(os.path.join(runs, f"cracks_{study}*"))
                  if os.path.isfile(os.path.join(d, "summary.csv")))


def points(sweep_dir: str):
    """(summary row, Run) of each point of one sweep's output directory, in the sweep's order; a point that
    failed (no output file) is given with Run None, so that a table can show it rather than drop it."""
    tab = table.read(os.path.join(sweep_dir, "summary.csv"))
    for i in range(len(tab["point"])):
        row = {k: tab[k][i] for k in tab}
        path = os.path.join(sweep_dir, str(row.get("out") or ""))
        yield row, (Run(path) if row.get("out") and os.path.exists(path) else None)


def provenance(rows: list[dict]) -> dict:
    """The provenance a figure drawn from ``rows`` is stamped with (``plot.figures.save``): their scenes and
    commits."""
    return {"scene": [r["scene"] for r in rows], "commit": [r["commit"] for r in rows]}


def write(rows: list[dict], cols: list[str], path: str) -> str:
    """``cols`` then ``scene`` and ``commit`` to the CSV at ``path``; returns the Markdown table of ``cols``."""
    table.write_csv(path, cols + ["scene", "commit"], rows)
    return table.markdown(rows, cols)


def tabulate(study: str, runs: str, img: str, tables: str) -> str:
    """Run study ``study``'s tabulation (see the module docstring)."""
    if study not in STUDIES:
        raise ValueError(f"study {study!r}: accepted: {', '.join(STUDIES)}")
    return _made(study, img, tables, lambda mod: mod.tabulate(runs, img, tables))


def refit(study: str, img: str, tables: str) -> str:
    """Study ``study``'s fits again from its tables under ``tables``, without its runs (``REFIT``)."""
    if study not in REFIT:
        raise ValueError(f"study {study!r}: accepted: {', '.join(REFIT)}")
    return _made(study, img, tables, lambda mod: mod.refit(tables, img))


def _made(study: str, img: str, tables: str, make) -> str:
    """``make(module)`` for the study's module, into ``img`` and ``tables``; the PDFs it leaves removed."""
    os.makedirs(img, exist_ok=True)
    os.makedirs(tables, exist_ok=True)
    md = make(importlib.import_module(f"parslip.studies.cracks.{study}"))
    # The page shows the PNGs; ``save`` also writes PDFs, which the docs do not keep.
    for f in glob.glob(os.path.join(img, f"cracks_{study}_*.pdf")):
        os.remove(f)
    return md
