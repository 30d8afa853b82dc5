"""Every table and figure of numbers under docs/ says which scene and commit it came from, and was
computed under today's model: a row (or a figure's run) whose readings differ from the schema's
defaults fails, unless its table varies that key.

The readings are the model choices a number depends on that a scene file usually leaves alone (the
issue that found docs/studies/friction.md computed under an older reading): the velocity unit of the
stiffnesses, the rest offset of a re-formed bond, plane strain or stress, which spring is k_n, the
re-bond rule and its distance, what the drive holds, the substrate's k_n, the damping and its form, and
the contact of unbonded sites.  The test
fails on a table computed before a default changed, which is how such a table gets regenerated.
"""
from __future__ import annotations

import csv
import json
import pathlib

import pytest

from parslip.plot.provenance import read_png
from parslip.scene.schema import SCHEMA

DOCS = pathlib.Path(__file__).resolve().parent.parent / "docs"
READINGS = ("material.velocity_unit", "interface.reform_x0", "material.model", "material.kn_spring",
            "interface.rebond", "interface.rebond_within", "drive.hold", "material.bottom_kn", "time.zeta",
            "time.damping", "interface.contact")
TABLES = sorted(DOCS.rglob("*.csv"))
FIGURES = sorted(DOCS.rglob("*.png"))


def _departures(scenes: list[dict], varied: set) -> list[str]:
    """'key = value (default ...)' for each reading a scene holds at a value other than today's default,
    leaving out the keys the table or figure varies."""
    bad = []
    for s in scenes:
        for key in READINGS:
            if key in varied or key not in s:
                continue
            if s[key] != SCHEMA[key].default:
                bad.append(f"{key} = {s[key]!r} (default {SCHEMA[key].default!r})")
    return sorted(set(bad))


def _varied(scenes: list[dict]) -> set:
    """The keys that take more than one value over ``scenes``: what a sweep or a comparison varies."""
    keys = set().union(*scenes) if scenes else set()
    return {k for k in keys if len({json.dumps(s.get(k), default=str) for s in scenes}) > 1}


def test_the_docs_hold_tables_and_figures():
    assert TABLES and FIGURES


@pytest.mark.parametrize("path", TABLES, ids=lambda p: str(p.relative_to(DOCS)))
def test_a_table_records_its_scene_and_commit_under_todays_readings(path):
    rows = list(csv.DictReader(path.open()))
    assert rows, path
    assert {"scene", "commit"} <= set(rows[0]), f"{path}: no scene and commit columns"
    ok = [r for r in rows if r["scene"]]
    assert ok and all(r["commit"] and r["commit"] != "unknown" for r in ok), f"{path}: a row without a commit"
    scenes = [json.loads(r["scene"]) for r in ok]
    cols = set(rows[0])
    # a column named by a key (in full or by its last part, as "damping" for time.damping), or the keys it sweeps
    varied = _varied(scenes) | cols | {k for k in READINGS if k.rsplit(".", 1)[-1] in cols}
    assert not _departures(scenes, varied), f"{path}: computed under other readings: {_departures(scenes, varied)}"


@pytest.mark.parametrize("path", FIGURES, ids=lambda p: str(p.relative_to(DOCS)))
def test_a_figure_records_its_scene_and_commit_under_todays_readings(path):
    p = read_png(path)
    assert p["commit"] and p["scenes"], f"{path}: no parslip:commit / parslip:scene (plot.provenance)"
    assert "unknown" not in p["commit"], path
    bad = _departures(p["scenes"], _varied(p["scenes"]) | _table_readings(path))
    assert not bad, f"{path}: drawn from runs under other readings: {bad}"


def _table_readings(figure) -> set:
    """The readings a figure's study table names as columns (by key's last part): a figure img/<stem>_*.png
    draws the runs of the table <stem>.csv beside its img folder, which declares them."""
    keys = set()
    for table in TABLES:
        if table.parent == figure.parent.parent and figure.stem.startswith(table.stem + "_"):
            cols = set(next(csv.reader(table.open())))
            keys |= {k for k in READINGS if k in cols or k.rsplit(".", 1)[-1] in cols}
    return keys


def test_the_check_fails_on_a_table_under_an_old_reading(tmp_path):
    """The friction study as it was (velocity unit c_s, rest offset 'current') fails the check."""
    old = dict((k, SCHEMA[k].default) for k in READINGS)
    old.update({"material.velocity_unit": "c_s", "interface.reform_x0": "current"})
    scenes = [dict(old, **{"load.FN": fn}) for fn in (0.5, 1.0)]
    assert _departures(scenes, _varied(scenes)) == ["interface.reform_x0 = 'current' (default 'zero')",
                                                    "material.velocity_unit = 'c_s' (default 'c_r')"]
    assert _departures(scenes, _varied(scenes) | {"material.velocity_unit", "interface.reform_x0"}) == []
