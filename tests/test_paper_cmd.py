"""`parslip paper` end to end on shrunken runs (seconds): claims.md/.json, figures, reuse, readings, bad input."""
import json
import os

import pytest

from parslip.studies.paper import claims as cl
from parslip.cli.main import main
from parslip.io.contract import read_status
from parslip.scene.load import load_scene_file, resolve
from parslip.studies.paper import study as st

HERE = os.path.dirname(__file__)


def test_paper_command_end_to_end(tmp_path, capsys):
    out = tmp_path / "paper"
    code = main(["paper", "-o", str(out), "--shrink", "--role", "push", "--role", "shear", "--role", "shear_maps"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "claims agree" in printed
    js = json.loads((out / "claims.json").read_text())
    assert len(js["claims"]) == len(cl.CLAIMS)
    assert {c["verdict"] for c in js["claims"]} <= set(cl.VERDICTS)
    by = {c["key"]: c for c in js["claims"]}
    assert by["pull_first"]["verdict"] == cl.NOT_MEASURED            # no pull run asked for
    assert by["push_first"]["verdict"] != cl.NOT_MEASURED
    assert js["share_agreeing"] == pytest.approx(js["counts"]["agrees"] / len(cl.CLAIMS))
    md = (out / "claims.md").read_text()
    assert md.count("\n| ") == len(cl.CLAIMS) + 2 + 2 + 3          # claims table, runs table (3 roles)
    for f in ("push/spacetime.png", "push/front_speed.png", "push/mode2_fit.csv", "shear/spacetime.png"):
        assert (out / "figures" / f).exists(), f
    assert len(list((out / "figures" / "shear").glob("map_sxy_t*.png"))) >= 1      # T0 maps from shear_maps
    assert [r["role"] for r in js["runs"]] == ["push", "shear", "shear_maps"]
    assert not any(r["reused"] for r in js["runs"])
    # a second call reuses every run it finds complete with the same scene
    mtime = os.path.getmtime(out / "runs" / "push.vtkhdf")
    assert main(["paper", "-o", str(out), "--shrink", "--role", "push", "--role", "shear", "--no-figures"]) == 0
    js2 = json.loads((out / "claims.json").read_text())
    assert all(r["reused"] for r in js2["runs"]) and os.path.getmtime(out / "runs" / "push.vtkhdf") == mtime
    assert js2["claims"] == [dict(c) for c in js["claims"]]
    # a run of another reading is made again
    assert main(["paper", "-o", str(out), "--shrink", "--role", "push", "--no-figures",
                 "--set", "drive.hold=xy"]) == 0
    js3 = json.loads((out / "claims.json").read_text())
    assert not js3["runs"][0]["reused"] and js3["reading"] == {"drive.hold": "xy"}


def test_readings_scan_on_one_reading(tmp_path, monkeypatch, capsys):
    """The scan with one reading and one role: the base and the flipped reading, each scored, and the
    per-claim table of what the base misses."""
    monkeypatch.setattr(st, "READINGS", (st.Reading("drive.hold", "held in", (("x", "x"), ("xy", "x and y"))),
                                         st.Reading("load.FN", "F_N", ((1.0, "total"), ("per_node", "per node")))))
    monkeypatch.setattr(st, "SCAN_ROLES", ("push",))
    res = st.scan_readings(str(tmp_path), shrink=True, numerics=False)
    labels = [r["label"] for r in res["settings"]]
    assert labels[0].startswith("base") and "drive.hold = 'xy'" in labels[1] and "load.FN = 'per_node'" in labels[2]
    assert res["settings"][2]["note"].startswith("refused: load.FN")          # 24 per node closes the gap
    assert res["settings"][2]["agree"] == 0
    n = sum(set(c.needs) <= {"push"} for c in cl.CLAIMS)
    assert all(r["of"] == n for r in res["settings"])
    md = (tmp_path / "readings.md").read_text()
    assert "| setting | kind |" in md and f"/ {n} |" in md
    assert os.path.exists(tmp_path / "readings" / "hold-xy" / "push.vtkhdf")


@pytest.mark.parametrize("args, words", [
    (["--role", "nope"], ["--role 'nope'", "accepted: push, pull"]),
    (["--set", "material.kn_spring=sideways"], ["material.kn_spring", "accepted: 'along' or 'across'"]),
    (["--set", "no.such=1"], ["no.such", "unknown key"]),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, args, words):
    assert main(["paper", "-o", str(tmp_path / "o"), "--shrink", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and all(w in err for w in words), err


def test_unwritable_output_is_exit_2(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["paper", "-o", str(f / "sub"), "--shrink"]) == 2
    assert "--out" in capsys.readouterr().err


@pytest.mark.parametrize("role, scene", [("push", "push.toml"), ("pull", "pull.toml"), ("shear", "shear.toml"),
                                         ("push_v0_1e-2", "push_v0_1e-2.toml"), ("shear_l500", "shear_l500.toml")])
def test_roles_are_the_shipped_scenes(role, scene):
    """Each role is its scene file under run/, but for the drive time and the output it needs."""
    ignore = ("drive.duration", "output.snapshots", "output.interface_dt", "output.fields")
    a = resolve(load_scene_file(os.path.join(HERE, "..", "run", scene)))
    b = resolve(st.role_scene(role))
    assert {k: v for k, v in a.items() if k not in ignore} == {k: v for k, v in b.items() if k not in ignore}


def test_readings_are_scene_keys_with_their_options():
    from parslip.scene.schema import SCHEMA
    keys = {r.key for r in st.READINGS}
    assert keys == {"material.velocity_unit", "material.kn_spring", "material.bottom_kn", "drive.hold",
                    "interface.rebond", "interface.rebond_within", "load.FN", "lattice.bottom_cols",
                    "material.model", "interface.reform_x0"}
    for r in st.READINGS:
        values = [v for v, _ in r.options]
        assert SCHEMA[r.key].default in values, r.key
        for v in values:
            if v != "per_node":
                resolve({r.key: v})


def test_role_scenes_scale_and_read_f_n_per_node():
    s = st.role_scene("shear_l300", {"lattice.bottom_cols": 200, "load.FN": "per_node"})
    assert (s["lattice.top_cols"], s["lattice.bottom_cols"], s["lattice.top_rows"]) == (300, 600, 30)
    assert s["load.FN"] == 300.0
    assert st.role_scene("shear_maps", maps_duration=68.0)["output.snapshots"] == 136


def test_t0_map_times_are_the_first_fronts_not_the_later_ones():
    """A shear run with three fronts: the maps show the first one's start, middle and end (Fig. 7a), clipped
    to the maps run's last snapshot, never a later front's time beyond it."""
    import numpy as np
    from helpers import DT, NS, blank, draw
    from parslip.analysis.results import Run
    iface = blank(1400)
    for k0 in (100, 500, 900):
        draw(iface, k0, 0, +1, 1, NS, 0.008, crack=True)
    shear = Run.from_arrays(iface, {"drive.mode": "shear", "drive.v0": 1e-4})
    maps = Run.from_arrays(iface, {"drive.mode": "shear"})
    maps.__dict__["snapshot_times"] = np.arange(0, 8.01, 0.5)
    t = st.first_front_times(shear, maps)
    assert t == pytest.approx([100 * DT, (100 + NS // 2) * DT, (100 + NS - 1) * DT])
    maps.__dict__["snapshot_times"] = np.arange(0, 6.01, 0.5)
    assert max(st.first_front_times(shear, maps)) == 6.0


def test_the_measurements_never_start_a_run():
    """studies.paper.measures and .claims only read runs: no engine, no subprocess, no import of the study
    that makes them; the runs start in studies.paper.study.run_scene alone."""
    import ast
    import parslip.studies.paper.claims
    import parslip.studies.paper.measures
    for mod in (parslip.studies.paper.measures, parslip.studies.paper.claims):
        tree = ast.parse(open(mod.__file__).read())
        names = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                names.add(("." * node.level) + (node.module or ""))
        assert not any("engine" in n or "subprocess" in n or "study" in n or "command" in n for n in names), \
            (mod.__name__, names)
    src = open(st.__file__).read()
    assert src.count("run(scene, out=out") == 1 and "def run_scene" in src and "subprocess" not in src


def test_paper_under_mpiexec_on_two_ranks(tmp_path):
    """Every run of the study uses both ranks, in-process (run_scene on the world communicator); one
    report, exit 0; the run file says it ran on 2 ranks."""
    from helpers import require, run_cli
    require("gather")
    p = run_cli(2, "paper", "-o", tmp_path / "p", "--shrink", "--role", "push", "--no-figures")
    assert p.returncode == 0, p.stderr
    assert p.stdout.count("claims agree") == 1
    js = json.loads((tmp_path / "p" / "claims.json").read_text())
    assert [r["role"] for r in js["runs"]] == ["push"] and js["runs"][0]["exit"] == 0
    import h5py
    with h5py.File(tmp_path / "p" / "runs" / "push.vtkhdf", "r") as f:
        assert f.attrs["n_ranks"] == 2 and read_status(f) == "complete"
