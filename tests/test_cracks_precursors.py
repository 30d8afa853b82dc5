"""The precursor study's fits (``parslip.studies.cracks.precursors``, docs/studies/cracks.md section 2): one line
of arrest length against F_T/F_N per reading, loading height, re-formation delay and normal load, as Katano et
al.'s lines move with F_z (their Fig. 2c), recovered exactly from drawn precursors, and fitted again from the
study's own tables without its runs."""
import csv

import numpy as np
import pytest

from parslip.analysis import table
from parslip.studies.cracks import precursors as pc


def _arrests():
    """Drawn precursors: under "current" at the low height, L/Lambda = 2 mu at F_N = 2 and 10 mu - 8 at F_N = 8,
    four each, on the same spread of mu (a pooled line through both would not fit either)."""
    rows = []
    for fn, slope, icpt in ((2.0, 2.0, 0.0), (8.0, 10.0, -8.0)):
        for k, mu in enumerate((1.0, 1.2, 1.5, 1.9)):
            rows.append({"sweep": "s", "point": f"p{int(fn)}", "reading": "current", "F_N": fn, "height": "low",
                         "heal_time": 0.0, "precursor": k, "mu_arrest": mu, "length_over_lambda": slope * mu + icpt,
                         "scene": "{}", "commit": "abc1234"})
    return rows


def test_each_normal_load_gets_its_own_line():
    fit = pc.fits(_arrests())
    assert sorted(fit) == [("current", "low", 0.0, 2.0), ("current", "low", 0.0, 8.0)]
    for key, slope, icpt in ((("current", "low", 0.0, 2.0), 2.0, 0.0), (("current", "low", 0.0, 8.0), 10.0, -8.0)):
        assert fit[key]["slope"] == pytest.approx(slope) and fit[key]["intercept"] == pytest.approx(icpt, abs=1e-9)
        assert fit[key]["r2"] == pytest.approx(1.0) and fit[key]["n_fit"] == 4
    pooled = pc.line_fit([a["mu_arrest"] for a in _arrests()], [a["length_over_lambda"] for a in _arrests()])
    assert pooled["r2"] < 0.9


def test_refit_from_the_tables_alone(tmp_path):
    """``refit`` reads cracks_precursors.csv and cracks_precursors_arrests.csv, writes each run's row with the fit
    of its own load and leaves every other column (the runs' scene and commit too) as it was."""
    arrests = _arrests()
    runs = [{c: 0 for c in pc.RUN_COLS} | {"sweep": "s", "point": f"p{int(fn)}", "reading": "current", "F_N": fn,
                                           "height": "low", "heal_time": 0.0, "n_precursors": 4, "slope": 99.0,
                                           "scene": "{}", "commit": "abc1234"} for fn in (2.0, 8.0)]
    table.write_csv(str(tmp_path / "cracks_precursors.csv"), pc.RUN_COLS + ["scene", "commit"], runs)
    table.write_csv(str(tmp_path / "cracks_precursors_arrests.csv"), pc.ARREST_COLS + ["scene", "commit"], arrests)
    md = pc.refit(str(tmp_path), str(tmp_path / "img"))
    assert "| p8 |" in md and (tmp_path / "img" / "cracks_precursors_length.png").exists()
    with open(tmp_path / "cracks_precursors.csv", newline="") as fh:
        got = list(csv.DictReader(fh))
    assert [float(r["slope"]) for r in got] == pytest.approx([2.0, 10.0])
    assert [r["n_fit"] for r in got] == ["4", "4"] and [r["commit"] for r in got] == ["abc1234"] * 2
    assert np.all([r["n_precursors"] == "4" for r in got])
