"""`parslip info`: every section present, the numbers it prints equal to what they claim to be (memory
from ``scene.memory.predict``, node updates from the step counts, output bytes from a real file), and
what it says the engine leaves out listed exactly where it applies."""
import dataclasses
import os
import re
import subprocess
import sys

import h5py
import pytest

from helpers import FREE_BLOCK, SMALL, cli_env, scene, small_toml
from parslip.cli import main
from parslip.scene.memory import BASE, predict
from parslip.scene import budget, presets
from parslip.scene.derive import derive
from parslip.scene.load import load_scene_text, parse_set, resolve

LABELS = ("scene", "lattice", "top block", "substrate", "interface", "weakening", "law scales", "wave speeds",
          "Rayleigh speed", "surface wave", "stability", "time step", "steps", "cost", "memory", "output", "ranks",
          "left out", "warnings")


def _info(capsys, tmp_path, *argv, **over):
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**over))
    code = main(["info", str(sc), *argv])
    cap = capsys.readouterr()
    assert code == 0, cap.err
    return cap.out, str(sc)


def _sections(out: str) -> dict[str, list[str]]:
    """label -> its lines (a line with a blank label continues the one above)."""
    sec, last = {}, None
    for line in out.splitlines():
        label, text = line[:17].strip(), line[17:]
        if label:
            last = label
            sec[label] = [text]
        else:
            sec[last].append(text)
    return sec


def _mib(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"([0-9.]+) MiB", text)]


def test_info_has_every_section_in_order(capsys, tmp_path):
    out, _ = _info(capsys, tmp_path)
    labels = list(_sections(out))
    assert labels[:len(LABELS)] == list(LABELS)


# Scene overrides -> the items `left out` must list (and no other).
LEFT_OUT = [
    ({}, {"stresses", "fixed row"}),
    ({"time.zeta": 0.0}, {"stresses", "fixed row", "damping"}),
    ({"output.snapshots": 0}, {"snapshots", "fixed row"}),
    ({"output.fields": "interface"}, {"snapshots", "fixed row"}),
    ({"lattice.substrate": "rigid"}, {"stresses", "substrate"}),
    ({"lattice.substrate": "rigid", "time.zeta": 0.0, "output.snapshots": 0}, {"snapshots", "damping", "substrate"}),
    (FREE_BLOCK, {"snapshots", "damping"}),
]


@pytest.mark.parametrize("over,items", LEFT_OUT)
def test_info_lists_what_is_left_out_exactly_where_it_applies(capsys, tmp_path, over, items):
    out, _ = _info(capsys, tmp_path, **over)
    listed = {line.split(":")[0] for line in _sections(out)["left out"]}
    assert listed == items, out
    st = derive(scene(**{**SMALL, **over}))
    assert {k for k, _ in budget.left_out(st)} == items


def test_left_out_savings_are_the_counts_they_name(capsys, tmp_path):
    """fixed row: bottom_cols node updates a step; damping: 2 multiplications per integrated node a step;
    rigid: bottom_rows x bottom_cols nodes a step and the difference of predict() with and without them;
    snapshots: the bytes of 21 snapshots and predict()'s difference."""
    st = derive(scene(**{**SMALL, "time.zeta": 0.0}))
    out, _ = _info(capsys, tmp_path, **{"time.zeta": 0.0})
    sec = {line.split(":")[0]: line for line in _sections(out)["left out"]}
    n = st.n_steps
    assert "(40 nodes)" in sec["fixed row"] and f"40 node updates per step, {40 * n:.3g} over" in sec["fixed row"]
    integrated = st.lattice.n_nodes - 40
    assert f"{2 * integrated} per step, {2 * integrated * n:.3g} over the run" in sec["damping"]

    rigid = derive(scene(**{**SMALL, "lattice.substrate": "rigid"}))
    out, _ = _info(capsys, tmp_path, **{"lattice.substrate": "rigid"})
    line = next(x for x in _sections(out)["left out"] if x.startswith("substrate"))
    assert "4 x 40 = 160 nodes" in line and f"160 node updates per step ({160 * rigid.n_steps:.3g} over" in line
    mem, _ = _mib(line)
    # The nodes alone, at the rigid scene's step counts: predict() of the same setup on the elastic lattice.
    alt = dataclasses.replace(rigid, lattice=derive(scene(**SMALL)).lattice)
    assert mem == pytest.approx((predict(alt, 1)["total"] - predict(rigid, 1)["total"]) / 2 ** 20, rel=1e-2)

    st = derive(scene(**{**SMALL, "output.snapshots": 0}))
    out, _ = _info(capsys, tmp_path, **{"output.snapshots": 0})
    line = next(x for x in _sections(out)["left out"] if x.startswith("snapshots"))
    assert "against 21 snapshots" in line
    with_snaps = derive(scene(**{**SMALL, "output.snapshots": 20}))
    mem, disk = _mib(line)
    assert disk == pytest.approx(budget.output_bytes(with_snaps)["snapshots"] / 2 ** 20, rel=1e-2)
    assert mem == pytest.approx((predict(with_snaps, 1)["total"] - predict(st, 1)["total"]) / 2 ** 20, rel=1e-2)


@pytest.mark.parametrize("ranks", [1, 3])
def test_info_memory_and_cost_agree_with_predict_and_the_steps(capsys, tmp_path, ranks):
    st = derive(scene(**SMALL))
    out, _ = _info(capsys, tmp_path, "--ranks", str(ranks))
    sec = _sections(out)
    steps = [int(x) for x in re.findall(r"\d+", sec["steps"][0].split("(")[0])]
    assert steps == [st.n_ramp, st.n_settle, st.n_drive, st.n_steps]
    cost = sec["cost"][0]
    assert f"({st.lattice.n_nodes} nodes x {st.n_steps} steps)" in cost
    assert float(cost.split()[0]) == pytest.approx(st.lattice.n_nodes * st.n_steps, rel=1e-3)
    wall = st.lattice.n_nodes * st.n_steps / (budget.THROUGHPUT["float64"] * ranks)
    assert f"about {wall:.3g} s of time loop on {ranks} rank(s) at 600 M node-updates/s per rank (float64" in cost
    mem = predict(st, ranks)
    big, total = _mib(sec["memory"][0])[:2]
    assert big == pytest.approx(max(mem["per_rank"]) / 2 ** 20, abs=0.051)
    assert total == pytest.approx(mem["total"] / 2 ** 20, abs=0.051)
    assert f"{mem['bytes_per_node']:.0f} B per node beyond {BASE / 2 ** 20:.1f} MiB" in sec["memory"][0]
    assert f"on {ranks} rank(s)" in sec["memory"][0]


def test_float32_halves_the_predicted_wall_time(capsys, tmp_path):
    out64, _ = _info(capsys, tmp_path)
    out32, _ = _info(capsys, tmp_path, **{"time.precision": "float32"})
    t64 = float(re.search(r"about ([0-9.e+-]+) s", _sections(out64)["cost"][0]).group(1))
    t32 = float(re.search(r"about ([0-9.e+-]+) s", _sections(out32)["cost"][0]).group(1))
    assert t32 == pytest.approx(t64 / 2, rel=0.01)          # printed to 3 digits


def _data_bytes(path) -> int:
    """Bytes of data in every dataset of an HDF5 file but the bond events, whose number the physics decides;
    those are checked against ``budget.EVENT_FILE_BYTES`` per event here."""
    sizes, events = [], []
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: (events if "/events/" in name else sizes).append(obj.size * obj.dtype.itemsize)
                     if isinstance(obj, h5py.Dataset) else None)
        n_events = int(f["interface/events"].attrs["events_written"])
    assert sum(events) == budget.EVENT_FILE_BYTES * n_events
    return sum(sizes)


def test_output_size_is_the_data_a_run_writes(small_run, tmp_path):
    """output_bytes() against the datasets of real runs: the session's SMALL push (elastic, snapshots)
    and a rigid run with interface frames only."""
    with h5py.File(small_run, "r") as f:
        sc = resolve(load_scene_text(f.attrs["scene"]))
    assert budget.output_bytes(derive(sc))["total"] == _data_bytes(small_run)
    scp = tmp_path / "rigid.toml"
    scp.write_text(small_toml(**{"lattice.substrate": "rigid", "drive.duration": 1.0, "output.snapshots": 2}))
    out = tmp_path / "rigid.vtkhdf"
    assert main(["run", str(scp), "--out", str(out), "--quiet", "--no-png"]) == 0
    with h5py.File(out, "r") as f:
        sc = resolve(load_scene_text(f.attrs["scene"]))
    ob = budget.output_bytes(derive(sc))
    assert ob["total"] == _data_bytes(out) and ob["snapshots"] > 0


def test_quick_look_line_is_a_ready_command(capsys, tmp_path):
    out, path = _info(capsys, tmp_path, "--set", "drive.v0=0.03")
    line = _sections(out)["quick look"][0]
    assert line.startswith(f"parslip run {path} --set drive.v0=0.03 --set ")
    sets = [parse_set(x) for x in line.split("--set ")[1:]]
    resolved = resolve(load_scene_text(small_toml()), [(k, v) for k, v in sets])
    assert resolved["drive.v0"] == 0.03 and presets.differences(resolved, presets.QUICK_LOOK) == []
    out, _ = _info(capsys, tmp_path, **presets.QUICK_LOOK)
    assert "quick look" not in out


def test_ranks_beyond_the_columns_are_refused(capsys, tmp_path):
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml())
    for bad in ("0", "41"):
        assert main(["info", str(sc), "--ranks", bad]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"--ranks {bad}" in err[0] and "accepted: 1 to 40" in err[0]


def test_info_never_loads_mpi(tmp_path):
    """`parslip info` runs anywhere, MPI or not: it never imports mpi4py.MPI."""
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml())
    code = ("import sys; from parslip.cli import main; main(['info', %r]); "
            "print('mpi4py.MPI' in sys.modules)" % str(sc))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=cli_env())
    assert p.returncode == 0 and p.stdout.strip().splitlines()[-1] == "False", p.stderr


def test_the_guide_shows_what_info_prints_today(capsys, monkeypatch):
    """docs/guide/info.md's example is `parslip info run/push.toml --ranks 2` as it prints today, line for line:
    a change of a default, the memory model or the output's contents that moves a number fails here, and the
    page is regenerated by pasting the command's output."""
    import pathlib
    root = pathlib.Path(__file__).resolve().parent.parent
    page = (root / "docs" / "guide" / "info.md").read_text()
    cmd = "$ parslip info run/push.toml --ranks 2\n"
    shown = page[page.index(cmd) + len(cmd):].split("```", 1)[0]
    cwd = os.getcwd()
    # The page shows the scaling model with its default coefficients, not those a benchmark kept on this host.
    monkeypatch.setattr("parslip.io.cache.load_coefficients", lambda: None)
    try:
        os.chdir(root)
        assert main(["info", "run/push.toml", "--ranks", "2"]) == 0
    finally:
        os.chdir(cwd)
    assert capsys.readouterr().out.splitlines() == shown.splitlines()
