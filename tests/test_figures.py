"""Figure code: the numbers the figures plot against independent computations, and `parslip figures` /
`parslip compare` writing their files."""
import os

import numpy as np
import pytest

import parslip
from parslip.plot import figures
from parslip.cli import analysis_cmds, main


def test_figure_names_match_the_command_line():
    assert analysis_cmds.FIGURE_NAMES == figures.FIGURES


def test_slip_velocity_of_the_driven_edge_is_v0(small_run):
    """Push drives the rear face, interface node included: u(x = 0) = v0 t, so u-dot = v0 exactly."""
    run = parslip.open(small_run)
    t, v = figures.slip_velocity(run, 0.0)
    assert np.median(v[1:-1]) == pytest.approx(run.v0, rel=1e-6)
    # and ahead of the edge the site moves in jumps: faster than v0 while a pulse passes
    assert figures.slip_velocity(run, 0.5)[1].max() > 2 * run.v0


def test_stress_profiles_and_leading_tip(small_run):
    run = parslip.open(small_run)
    fr = run.fronts()
    times = figures.stress_times(run)
    assert times == [f.nucleation_time for f in fr[:4]]                    # pulses: the nucleation times
    t = float(fr[0].tip["t"][len(fr[0].tip["t"]) // 2])                   # front 1 halfway across
    f1, x1 = figures.leading_tip(fr, t)
    assert f1 is fr[0] and x1 == fr[0].tip_at(t) and x1 > 0.3
    xi, s = figures.tip_profile(run, fr[0], t, "sxy")
    k = run.frame_at(t)
    assert np.all(xi > 0) and len(xi) == 8
    np.testing.assert_array_equal(s, run.interface["sxy"][k, np.argsort(run.x)][np.isin(run.x, x1 + xi)])
    assert np.all(run.interface["intact"][k, np.isin(run.x, x1 + xi)] == 1)   # the bonds ahead are intact
    rows = figures.mode2_table(run)
    assert rows and all(r["front"] in (1, 2, 3) for r in rows)


def test_a_lone_front_is_profiled_along_its_run():
    """One crack across the contact (as in T0): four moments from its start to its end (Fig. 7b)."""
    from helpers import blank, draw
    from parslip.analysis.results import Run
    iface = blank(200)
    arr = draw(iface, 30, 0, +1, 2, 1, 0.01, crack=True)
    run = Run.from_arrays(iface, {"drive.mode": "shear", "drive.v0": 1e-4})
    t = run.times[arr]
    assert figures.stress_times(run) == pytest.approx([t[0], t[20], t[39], t[-1]])
    assert figures.map_times(run) == pytest.approx([t[0], t[30], t[-1]])


def test_slip_behind_tips_subtracts_the_drive_to_the_previous_nucleation(small_run):
    run = parslip.open(small_run)
    fr = run.fronts()
    x, du, dv = figures.slip_behind_tips(run, 1)
    np.testing.assert_allclose(du, fr[1].tip["u_behind"] - run.v0 * fr[0].nucleation_time)
    # the site behind the tip at its arrival: read it straight from the interface record
    j = 5
    k = fr[1].tip["frame"][j]                   # the first frame that shows the tip's break
    s = figures.site_index(run, fr[1].tip["x"][j - 1])
    assert fr[1].tip["u_behind"][j] == run.interface["ux"][k, s] - run.interface["ux"][0, s]
    assert dv[j] == run.interface["uy"][k, s] - run.interface["uy"][0, s]


def test_passages_mark_each_front_at_a_site(small_run):
    run = parslip.open(small_run)
    s = figures.site_index(run, 0.5)
    marks = figures.passages(run, s)
    crossing = [i for i, f in enumerate(run.fronts()) if f.tip["x"].max() >= run.x[s]]
    assert [i for i, _ in marks] == crossing
    for _, t in marks:                              # the bond breaks at t, between frames k - 1 and k
        k = int(np.searchsorted(run.times, t, side="right"))
        assert run.interface["intact"][k, s] == 0 and run.interface["intact"][k - 1, s] == 1


def test_figures_command_writes_the_set(small_run, tmp_path, capsys):
    out = tmp_path / "figs"
    assert main(["figures", small_run, "-o", str(out)]) == 0
    names = set(os.listdir(out))
    for fig in ("spacetime", "front_speed", "interface_stress", "slip_records", "slip_behind_tips",
                "slip_velocity", "pulse_width", "mode2_fit"):
        assert {f"{fig}.png", f"{fig}.pdf"} <= names
        assert (out / f"{fig}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (out / f"{fig}.pdf").read_bytes()[:5] == b"%PDF-"
    rows = (out / "mode2_fit.csv").read_text().splitlines()
    assert rows[0].startswith("front,t_l_per_cr,K_II") and len(rows) > 1
    have_render = os.path.exists(os.path.join(os.path.dirname(figures.__file__), "render.py"))
    assert any(n.startswith("map_sxy") for n in names) == have_render


def test_compare_command_tabulates_speed_over_v0(small_run, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", small_run, small_run, "-o", str(out), "--scale", "v0", "--fronts", "2"]) == 0
    lines = (out / "compare_speed.csv").read_text().splitlines()
    assert len(lines) == 1 + 2 * 2
    run = parslip.open(small_run)
    f = run.fronts()[0]
    cells = lines[1].split(",")
    assert float(cells[4]) == pytest.approx(f.mean_speed, rel=1e-5)
    assert float(cells[5]) == pytest.approx(f.mean_speed / run.v0, rel=1e-5)
    assert (out / "compare_speed.png").exists() and (out / "compare_speed.pdf").exists()


@pytest.mark.parametrize("argv,message", [
    (["figures", "RUN", "-o", "OUT", "--only", "nope"], "--only 'nope': unknown figure; accepted: spacetime"),
    (["figures", "/nonexistent.vtkhdf", "-o", "OUT"], "RUN '/nonexistent.vtkhdf': no such file"),
    (["compare", "RUN", "-o", "OUT", "--scale", "x"], "--scale 'x': unknown; accepted: auto, v0, c_r"),
])
def test_bad_input_one_line(argv, message, small_run, tmp_path, capsys):
    argv = [small_run if a == "RUN" else str(tmp_path) if a == "OUT" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err


def test_a_run_without_fronts_still_gets_its_figures(tmp_path):
    """Before the first break (a short shear run) every figure is drawn, empty where there is no front."""
    from helpers import blank
    from parslip.analysis.results import Run
    iface = blank(50)
    iface["sxy"] = iface["syy"] = np.zeros_like(iface["ux"])
    run = Run.from_arrays(iface, {"drive.mode": "shear", "drive.v0": 1e-4})
    paths = figures.write_all(run, str(tmp_path))
    assert sum(p.endswith(".png") for p in paths) == 8          # all but the stress maps (no snapshots)
    assert (tmp_path / "mode2_fit.csv").read_text().count("\n") == 1


def _run(k0s, nf, crack=False, fps=1):
    from helpers import blank, draw
    from parslip.analysis.results import Run
    iface = blank(nf)
    for k0 in k0s:
        draw(iface, k0, 0, +1, fps, 2, 0.01, crack=crack)
    iface["sxy"] = iface["syy"] = np.zeros_like(iface["ux"])
    return Run.from_arrays(iface, {"drive.mode": "shear", "drive.v0": 1e-4})


def test_a_lone_fast_front_gets_a_zoomed_space_time_panel(tmp_path):
    """A crack crossing the 60 sites in 60 of 2000 frames (3 % of the record) is framed from 0.5 l/c_r
    before it to 2 l/c_r after its last site; a train of pulses filling the record is not zoomed."""
    from helpers import DT, NS
    lone = _run([1500], 2000, crack=True)
    t0, t1 = figures.zoom_window(lone)
    assert t0 == pytest.approx(1500 * DT - 0.5) and t1 == pytest.approx((1500 + NS - 1) * DT + 2.0)
    assert figures.zoom_window(_run([10, 300, 600], 1000, fps=4)) is None
    png, _ = figures.fig_spacetime(lone, str(tmp_path))
    from PIL import Image
    w, h = Image.open(png).size
    assert w > h                                                # two panels side by side


def test_stress_map_times_on_one_snapshot_are_drawn_once_and_said(tmp_path, monkeypatch):
    """Three map times 0.3 l/c_r apart with snapshots 4 l/c_r apart fall on one snapshot: one file, and
    a logged note that the snapshots are too sparse."""
    import logging

    from parslip.plot import render
    drawn, notes = [], []
    monkeypatch.setattr(render, "render_frame", lambda run, field, t, png: drawn.append((field, t, png)))

    class Snaps:
        snapshot_times = np.array([0.0, 4.0, 8.0])

    class Keep(logging.Handler):        # the parslip logger may not propagate (the command line set it up)
        def emit(self, record):
            notes.append(record.getMessage())
    logger, handler = logging.getLogger("parslip"), Keep()
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    try:
        out = figures.fig_stress_maps(Snaps(), str(tmp_path), fields=("sxy",), times=[4.1, 4.4, 4.7])
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    assert [os.path.basename(p) for p in out] == ["map_sxy_t0004.00.png"] and len(drawn) == 1
    assert any("too sparse" in n for n in notes)


def test_push_against_pull_speeds_on_a_log_axis(small_run, tmp_path, monkeypatch):
    """In c_r scale the speeds span slow pulses and their run-up to c_r: a log axis; v/v0 stays linear."""
    run = parslip.open(small_run)
    scales = []
    real_save = figures.save
    monkeypatch.setattr(figures, "save", lambda fig, d, name, source=None: scales.append(
        [ax.get_yscale() for ax in fig.axes if ax.get_lines()]) or real_save(fig, d, name, source))
    figures.compare_speeds([run, run], str(tmp_path), n=1, scale="c_r")
    figures.compare_speeds([run, run], str(tmp_path), n=1, scale="v0")
    assert scales == [["log"], ["linear"]]


def test_a_figure_carries_the_scene_and_commit_it_was_drawn_from(tmp_path):
    """plot.provenance: savefig's text chunks, a stamp on a finished PNG, read back the same."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from parslip.plot import provenance
    from parslip.plot.figures import save
    src = {"scene": {"drive.mode": "push", "load.FN": 1.0}, "commit": "abc123"}
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    png, pdf = save(fig, str(tmp_path), "f", src)
    assert provenance.read_png(png) == {"commit": ["abc123"], "scenes": [src["scene"]]}
    table = {"scene": ['{"load.FN": 1.0}', '{"load.FN": 2.0}'], "commit": ["c1", "c1"]}
    provenance.stamp_png(png, table)
    assert provenance.read_png(png) == {"commit": ["c1"], "scenes": [{"load.FN": 1.0}, {"load.FN": 2.0}]}
    assert b"parslip:commit c1" not in open(pdf, "rb").read() and b"abc123" in open(pdf, "rb").read()
