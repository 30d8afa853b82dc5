"""Large contacts: the l = 500 and l = 1000 scenes, the decomposition on 64 ranks, and the scaling model.

The 64-rank layout is checked against an independent reading of the slabs:
the owner of a global column is found from the slab bounds alone, and the
halo a row must hold from the scene's slip reach by the formula of
``parallel.layout.Reach``, so a halo segment drawn from the wrong rank, or
a halo too short for the slip, shows.  The scaling fit is checked on
synthetic points with known coefficients.
"""
import math
import os

import numpy as np
import pytest

from parslip.studies.bench import scaling
from parslip.scene.load import load
from parslip.model.lattice import BOTTOM, TOP, Lattice
from parslip.parallel.layout import build_layout, interface_reach
from parslip.scene.derive import derive

RUN = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "run")
LARGE = {"push_l500": ("push", 500), "shear_l500": ("shear", 500), "push_l1000": ("push", 1000),
         "shear_l1000": ("shear", 1000)}


@pytest.mark.parametrize("name", sorted(LARGE))
def test_large_scenes_keep_the_paper_aspect_ratio_and_cadence(name):
    """Top 10 x 100 and substrate 20 x 300 at l = 100, scaled; 100 interface frames per l/c_r; a header."""
    mode, l = LARGE[name]
    path = os.path.join(RUN, f"{name}.toml")
    sc = load(path, [])
    s = l // 100
    assert (sc["lattice.top_rows"], sc["lattice.top_cols"]) == (10 * s, 100 * s)
    assert (sc["lattice.bottom_rows"], sc["lattice.bottom_cols"]) == (20 * s, 300 * s)
    assert sc["drive.mode"] == mode
    assert sc["drive.v0"] == (1e-3 if mode == "push" else 1e-4)     # as run/push.toml and run/shear.toml
    assert sc["drive.duration"] == 100.0
    st = derive(sc)
    # One frame per 0.01 l/c_r = l/100 a/c_r: steps per frame is the floor of (l/100)/c_r/dt.
    assert st.frame_every == math.floor(l / 100 / st.material.c_r / st.dt)
    assert 10_000 <= st.n_frames <= 10_100
    with open(path) as f:
        head = f.read().split("[lattice]")[0]
    assert "Units:" in head and f"l = {l}" in head and "interface frame" in head and "snapshots" in head


def _owner(bounds, c):
    """Rank owning global column c, from the slab bounds alone."""
    return int(np.searchsorted(bounds, c, side="right")) - 1


@pytest.fixture(scope="module")
def l500_on_64():
    # Halos fixed for the scene's whole travel (an explicit slip reach): wide halos reaching several slabs.
    st = derive(load(os.path.join(RUN, "push_l500.toml"), ["interface.slip_reach=52"]))
    lays = [build_layout(st.lattice, r, 64, st.reach, "push") for r in range(64)]
    return st, lays


def test_l500_push_on_64_ranks_every_halo_segment_comes_from_its_owner(l500_on_64):
    """Every rank's HALO columns, row by row, arrive exactly once, each from the rank owning that column."""
    st, lays = l500_on_64
    lat = st.lattice
    bounds = lays[0].bounds
    assert len(bounds) == 65 and bounds[0] == 0 and bounds[-1] == lat.ncols and np.all(np.diff(bounds) >= 1)
    # The slip the scene's drive reaches, v0 x duration = 1e-3 c_r x 100 l/c_r = 0.1 l = 50 a, plus 2 a; link = 1 a
    # (delta_b = 0.7, and a free site looks for substrate sites within delta0 + 1/2 = 1 a in x).
    assert st.slip_reach == pytest.approx(52.0)
    top_halo, bottom_halo = 52 + 5 * 1 + 1, 52 + 4 * 1 + 1
    widest_slab = int(np.diff(bounds[(bounds >= lat.top.col0) & (bounds <= lat.top.col0 + lat.top.cols)]).max())
    assert top_halo > 3 * widest_slab              # under the contact a halo spans more than three slabs
    for lay in lays:
        c0, c1 = lay.col_range
        for b in (BOTTOM, TOP):
            blk = lat.blocks[b]
            span = (blk.col0, blk.col0 + blk.cols)
            for r in range(blk.rows):
                h = 1
                if b == TOP and r == 0:
                    h = top_halo
                elif b == BOTTOM and r == blk.rows - 1:
                    h = bottom_halo
                own = set(range(max(c0, span[0]), min(c1, span[1])))
                # A rank holds the halo of a row even where it owns none of it: its substrate sites beside
                # the contact see the block's interface nodes that slide over them.
                want = set(range(max(c0 - h, span[0]), min(c1 + h, span[1]))) - own
                got = []
                for p in lay.peers:
                    for sg in p.recv:
                        if sg.block == b and sg.row == r:
                            assert all(_owner(bounds, c) == p.rank for c in range(sg.lo, sg.hi)), \
                                (lay.rank, p.rank, b, r, sg)
                            got += range(sg.lo, sg.hi)
                assert len(got) == len(set(got)), (lay.rank, b, r)          # no column twice
                assert set(got) == want, (lay.rank, b, r)
        # Interface bond state travels for exactly the block's HALO interface sites, from their owners.
        sites = [c for p in lay.peers for lo, hi in p.recv_sites for c in range(lo, hi)
                 if _owner(bounds, c) == p.rank]
        assert sorted(sites) == sorted(c for p in lay.peers for lo, hi in p.recv_sites for c in range(lo, hi))


def test_l500_push_on_64_ranks_what_one_sends_the_other_receives(l500_on_64):
    """Rank p's send list to q is q's receive list from p, segment for segment; peers are mutual."""
    _, lays = l500_on_64
    key = lambda segs: sorted((s.block, s.row, s.lo, s.hi) for s in segs)     # noqa: E731
    for lay in lays:
        for p in lay.peers:
            back = {q.rank: q for q in lays[p.rank].peers}
            assert lay.rank in back
            assert key(p.send) == key(back[lay.rank].recv)
            assert sorted(p.send_sites) == sorted(back[lay.rank].recv_sites)
    hops = max(abs(p.rank - lay.rank) for lay in lays for p in lay.peers)
    assert hops >= 4                                # multi-hop: peers beyond the next slab


def test_halo_values_count_what_the_exchange_plan_packs(l500_on_64):
    """``scaling.rank_share`` counts from the layout; the exchange plan sizes its buffers by its own loop."""
    from parslip.parallel.halo_mpi import build_plan
    st, lays = l500_on_64
    for r in (0, 5, 21, 32, 63):
        share = scaling.rank_share(st.lattice, lays[r])
        plan = build_plan(lays[r], np.float64)
        assert share.values_sent == plan.sb_ptr[-1] and share.values_received == plan.rb_ptr[-1]
        assert share.messages == 2 * len(plan.peer)
        c0, c1 = lays[r].col_range
        assert share.nodes == len(st.lattice.nodes_in_columns(c0, c1)["gid"])
    shares = scaling.rank_shares(st, 64)
    assert sum(s.nodes for s in shares) == st.lattice.n_nodes
    assert sum(s.sites for s in shares) == st.lattice.n_top_sites


def test_features_of_a_strip_cut_in_two_drawn():
    """A free 4-row strip of 10 columns on 2 ranks (bulk rows only, a halo of one column):

        column      0 1 2 3 4 | 5 6 7 8 9
        rank 0      O O O O O | H
        rank 1              H | O O O O O

    each rank receives 4 halo nodes (x and y: 8 values) and sends 4: H = 16, M = 2.
    """
    lat = Lattice(4, 10, 0, 0)
    shares = [scaling.rank_share(lat, build_layout(lat, r, 2, interface_reach(0.5, 0.7, 0.0))) for r in (0, 1)]
    for s in shares:
        assert (s.nodes, s.sites, s.values_sent, s.values_received, s.messages) == (20, 0, 8, 8, 2)
        assert s.peers == [1 - s.rank] and s.halo_bulk == 1 and s.hops == 1
    assert scaling.features(shares) == {"N": 20, "S": 0, "H": 16, "M": 2, "1": 1}


def _synthetic(coef, noise=0.0, seed=1):
    rng = np.random.default_rng(seed)
    pts = []
    for l in (100, 200, 300, 500, 700, 1000):
        for ranks in (1, 2):
            n = 0.7 * l * l / ranks
            h = 0 if ranks == 1 else 4.4 * l
            f = {"N": n, "S": l / ranks, "H": h, "M": 2 * (ranks - 1), "1": 1}
            t = coef["a"] * n + coef["b"] * h + coef["c"]
            pts.append({"l": l, "ranks": ranks, "features": f, "us_per_step": t * (1 + noise * rng.standard_normal())})
    return pts


def test_fit_recovers_known_coefficients():
    """Noise-free points give back a, b, c to rounding; with 2 % noise they lie within 4 standard errors."""
    true = {"a": 1.6e-3, "b": 0.012, "c": 9.0}
    f = scaling.fit(_synthetic(true), ("N", "H", "1"))
    for k, v in true.items():
        assert f.coef[k] == pytest.approx(v, rel=1e-9)
    assert f.rms_rel < 1e-12
    noisy = scaling.fit(_synthetic(true, noise=0.02), ("N", "H", "1"))
    for k, v in true.items():
        assert noisy.stderr[k] > 0
        assert abs(noisy.coef[k] - v) < 4 * noisy.stderr[k], (k, noisy.coef[k], noisy.stderr[k])
    assert 0.005 < noisy.rms_rel < 0.05
    assert np.allclose(noisy.residuals(), [noisy.predict(p["features"]) / p["us_per_step"] - 1 for p in noisy.points])


def test_fit_refuses_terms_the_points_cannot_tell_apart():
    """On one rank count M is the same for every point, so it cannot be told from c; fewer points than terms."""
    one = [p for p in _synthetic({"a": 1e-3, "b": 0.0, "c": 5.0}) if p["ranks"] == 2]
    with pytest.raises(ValueError, match="cannot determine"):
        scaling.fit(one, ("N", "M", "1"))
    with pytest.raises(ValueError, match="cannot determine"):
        scaling.fit(one[:2], ("N", "H", "1"))


def test_cluster_prediction_adds_latency_and_bandwidth_and_hides_what_the_interior_covers():
    """t = compute + b H + exposed network, by hand for one rank share."""
    f = scaling.Fit(terms=("N", "H", "1"), coef={"a": 1e-3, "b": 0.01, "c": 10.0}, stderr={}, points=[],
                    rms_rel=0.0)
    share = scaling.RankShare(rank=1, cols=(10, 20), nodes=40_000, sites=0, values_sent=1000, values_received=1000,
                              peers=[0, 2, 3], halo_top=(0, 0), halo_bottom=(0, 0), halo_bulk=1)
    compute = 1e-3 * 40_000 + 10.0                                  # 50 us
    network = 6 * 2.0 + 2000 * 8 / (10.0 * 1e3)                     # 6 messages x 2 us + 16 kB at 10 GB/s = 13.6 us
    exposed = scaling.predict(f, [share], scaling.Cluster(latency_us=2.0, bandwidth_gbs=10.0, overlap=False))
    assert exposed["network_us"] == pytest.approx(network)
    assert exposed["us_per_step"] == pytest.approx(compute + 0.01 * 2000 + network)
    hidden = scaling.predict(f, [share], scaling.Cluster(latency_us=2.0, bandwidth_gbs=10.0, overlap=True))
    assert hidden["exposed_network_us"] == 0.0                      # 13.6 us < the interior's 48.75 us
    assert hidden["us_per_step"] == pytest.approx(compute + 0.01 * 2000)
    slow = scaling.predict(f, [share], scaling.Cluster(latency_us=20.0, bandwidth_gbs=10.0, overlap=True,
                                                       throughput_ratio=2.0))
    interior = (1e-3 * 40_000 / 2 + 10.0) * (1 - 2000 / 80_000)
    assert slow["exposed_network_us"] == pytest.approx(6 * 20.0 + 1.6 - interior)


def test_measure_keeps_the_fastest_clean_repeat_resumes_and_survives_a_timeout(tmp_path, monkeypatch):
    """Cases stand in for bench.case: times given per (l, ranks) and repeat; a None is a case that timed out."""
    times = {(100, 1): [12.0, 11.0], (100, 2): [None, None], (200, 1): [40.0, 41.0]}
    calls = []

    def fake(l, ranks, seconds, mode, timeout):
        calls.append((l, ranks))
        t = times[(l, ranks)][sum(1 for c in calls if c == (l, ranks)) - 1]
        return None if t is None else {"us_per_step": t}

    monkeypatch.setattr(scaling, "run_case", fake)
    path = tmp_path / "points.json"
    pts = scaling.measure([100], [1, 2], repeats=2, quiet=None, path=str(path), log=lambda m: None)
    assert [(p["l"], p["ranks"], p["us_per_step"]) for p in pts] == [(100, 1, 11.0), (100, 2, None)]
    assert pts[0]["features"] == {"N": 7000, "S": 100, "H": 0, "M": 0, "1": 1}   # 10 x 100 + 20 x 300 nodes
    calls.clear()
    again = scaling.measure([100, 200], [1], repeats=2, quiet=None, path=str(path),
                            log=lambda m: None)
    assert calls == [(200, 1), (200, 1)]                  # l = 100 was kept from the file, not measured again
    assert [(p["l"], p["ranks"], p["us_per_step"]) for p in again] == [(100, 1, 11.0), (100, 2, None), (200, 1, 40.0)]
    (tmp_path / "bench.json").write_text('{"cases": []}')
    with pytest.raises(ValueError, match="not a file of scaling points"):
        scaling.measure([100], [1], path=str(tmp_path / "bench.json"), log=lambda m: None)


def test_bench_pack_takes_set_values_as_toml_literals_and_packs_what_the_model_counts():
    """`python -m parslip.studies.bench.pack L --set KEY=VALUE`: the value a TOML literal (the scaling model's
    latency is measured with ``run.exchange = "messages"``, a string), and the values it packs and unpacks
    those the travel model charges that rank (``parallel.counts``, in closed form)."""
    import json
    import subprocess
    import sys
    from parslip.parallel.counts import rank_counts
    from parslip.parallel.layout import slab_bounds
    from parslip.scene.derive import derive
    from parslip.studies.bench.case import scene_at
    p = subprocess.run([sys.executable, "-m", "parslip.studies.bench.pack", "100", "--mode", "push", "--seconds",
                        "0.05", *scaling.MESSAGES, "--set", "drive.v0=2e-3"], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    got = json.loads(p.stdout.strip().splitlines()[-1])
    st = derive(scene_at(100, "push", "float64", [("drive.v0", 2e-3)]))
    c = rank_counts(st.lattice, slab_bounds(st.lattice, 2), st.reach, (0, 0), st.overlap)
    assert (got["ranks"], got["rank"], got["peers"]) == (2, 1, 1)
    assert got["values_sent"] + got["values_received"] == int(c.values[1])
    assert got["ns_per_value"] > 0
