"""`parslip info SCENE [--set KEY=VALUE ...] [--ranks N]`: what a scene is and what it will cost.

Everything is derived before a run, without MPI: the lattice and its nodes,
the materials and wave speeds, the time step and how it was found, the steps
of each phase, the cost in node updates and wall time (``scene.budget``), the
memory per rank from ``scene.memory.predict``, the output size, the usable
rank counts, what the engine leaves out of this scene and what that saves,
the warnings ``scene.advice`` raises, and the quick-look preset when the
scene differs from it.  Each line starts with a 17-column label.
"""
from __future__ import annotations

import math

from ..errors import ConfigError
from ..scene import advice, budget, presets
from ..scene.load import load

LABEL = 17


def _mib(b: float) -> str:
    return f"{b / 2 ** 20:.1f} MiB"


def _duration(s: float) -> str:
    """Seconds as '42 s', '3.5 min' or '2.1 h'."""
    if s < 120:
        return f"{s:.3g} s"
    if s < 7200:
        return f"{s / 60:.3g} min"
    return f"{s / 3600:.3g} h"


def _line(label: str, text: str) -> str:
    return f"{label:{LABEL}s}{text}"


def _block(label: str, items: list[str]) -> list[str]:
    """A label on the first line, the items one per line beneath it ('none' for no items)."""
    items = items or ["none"]
    return [_line(label if i == 0 else "", item) for i, item in enumerate(items)]


def _lattice_lines(st, scene_path: str) -> list[str]:
    """The scene, the lattice (nodes integrated, fixed, driven; the substrate) and the top block."""
    s, lat, mat = st.scene, st.lattice, st.material
    top, bot = lat.top, lat.bottom
    n = lat.n_nodes
    fixed = n - budget.integrated_nodes(lat)
    driven = {"push": top.rows, "pull": top.rows, "shear": top.cols}.get(s["drive.mode"], 0)
    if s["drive.rows"]:
        driven = s["drive.rows"][1] - s["drive.rows"][0] + 1
    if lat.rigid:
        sub = f"substrate rigid: one row of {bot.cols} fixed interface sites, no nodes"
    elif lat.has_interface:
        sub = f"substrate {bot.rows} x {bot.cols} (elastic; its row AB fixed)"
    else:
        sub = "no substrate (a free block)"
    return [_line("scene", scene_path),
            _line("lattice", f"top block {top.rows} x {top.cols}, {sub}: {n} nodes ({n - fixed} integrated, "
                             f"{fixed} fixed, {driven} driven), contact l = {st.l:g} a, "
                             f"{lat.n_top_sites} interface sites"),
            _line("top block", f"nu = {mat.nu} ({mat.model}): k_n = {mat.kn_top:.6g}, k_t = {mat.kt_top:.6g} "
                               f"(m c^2/a^2)")]


def _interface_lines(st) -> list[str]:
    """The substrate's waves, the interface law, its sites when they differ, and healing."""
    from ..model.physics import born_wave_speeds
    s, lat, mat, law = st.scene, st.lattice, st.material, st.law
    top = lat.top
    cl_b, cs_b = born_wave_speeds(mat.kn_bottom, mat.kt_bottom)
    out = [_line("substrate", f"k_n = {mat.kn_bottom:.6g}, k_t = {mat.kt_bottom:.6g}: c_l = {cl_b:.6g}, "
                              f"c_s = {cs_b:.6g}" + (" (rigid: only its interface sites, fixed)"
                                                     if lat.rigid else "")),
           _line("interface", f"k_x = {law.kx:g}, k_y = {law.ky:g}, delta0 = {law.delta0:g} a, delta_b = "
                              f"{law.delta_b:g} a; F_N = {s['load.FN']:g} (the gap closes at N k_y delta0 = "
                              f"{law.closing_load(top.cols):.6g}): mean gap at rest "
                              f"{law.delta0 - s['load.FN'] / (top.cols * law.ky):.4g} a")]
    if not law.uniform:
        vals = law.site_values(lat.n_top_sites)
        out.append(_line("sites", "; ".join(
            f"{k} {v.min():.4g} to {v.max():.4g} (mean {v.mean():.4g}, cv {v.std() / v.mean():.3g})"
            if v.max() > v.min() else f"{k} {v[0]:.4g}" for k, v in vals.items()) + f" over {lat.n_top_sites} sites"
            + (f"; {len(law.patches)} patch(es)" if law.patches else "")
            + (f"; random {law.random[0]}: cv {law.random[1]:g}, correlation {law.random[2]:g} a, seed "
               f"{law.random[3]}" if law.random else "")))
    out += _rupture_lines(st)
    if law.heal:
        out.append(_line("healing", f"re-bond only below a relative slip velocity of {law.heal_speed:g} c_r"
                         * bool(law.heal_speed) + ("; " if law.heal_speed and law.heal_time else "")
                         + f"after claiming the same site for {law.heal_time:g} l/c_r" * bool(law.heal_time)))
    return out


def _rupture_lines(st) -> list[str]:
    """The law's weakening, friction and scales (``analysis.rupture.law_scales``), the held prestress and
    Andrews' S and L_c, the nucleation."""
    from ..analysis.rupture import law_scales
    law, held, z = st.law, st.drive.prestress, st.law.nucleation
    k = law_scales(st)
    where = f" over x = {list(held.x)} l" if held is not None else ""
    out = [_line("weakening", (f"D_c = {k['D_c']:.4g} a past the peak, secant unloading" if law.soften else
                               "none: a bond breaks at its peak (interface.softening = 0)")
                 + (f"; contact friction mu = {law.friction:g}" if law.friction else "")),
           _line("law scales", f"tau_p = {k['tau_p']:.4g}, tau_r = {k['tau_r']:.4g} rho c_r^2, Gamma = "
                               f"{k['Gamma']:.4g} m c_r^2/a at rest under F_N{where}: Lambda = 9 pi/16 M Gamma/"
                               f"(tau_p - tau_r)^2 = {k['Lambda']:.4g} a (M = {k['M']:.4g})")]
    if held is not None:
        out.append(_line("prestress", f"tau_0 = {k['tau_0']:g} rho c_r^2 held, then {held.settle:g} l/c_r to "
                                      f"settle: S = (tau_p - tau_0)/(tau_0 - tau_r) = {k['S']:.4g}, L_c = 2 M "
                                      f"Gamma/(pi (tau_0 - tau_r)^2) = {k['L_c']:.4g} a"))
    if z is not None:
        lo, hi = z.sites(st.lattice.n_top_sites)
        how = (f"a front from its centre at {z.speed:g} c_r, each site" if z.kind == "forced" else "every site")
        out.append(_line("nucleation", f"{z.kind}: sites {lo} to {hi - 1} (x = {list(z.x)} l), {how} weakening to "
                                       f"its residual over {z.duration:g} l/c_r, from {z.start:g} l/c_r after "
                                       + ("the prestress settled" if held is not None else "the drive's start")))
    return out


def _drive_lines(st) -> list[str]:
    """The drive, when it is more than a prescribed x on the whole face."""
    s = st.scene
    if not (s["drive.mode"] != "none" and (s["drive.spring"] > 0 or s["drive.rows"])):
        return []
    rows = s["drive.rows"]
    return [_line("drive", (f"through a spring of k_s = {s['drive.spring']:g} m c^2/a^2 per driven node to a "
                            f"rigid loader at v0" if s["drive.spring"] > 0 else "prescribed x")
                  + (f"; rows {rows[0]} to {rows[1]} of the face" if rows else ""))]


def _time_lines(st) -> list[str]:
    """Wave speeds, the stability limit, the time step and the steps of each phase."""
    s, mat = st.scene, st.material
    return [
        _line("wave speeds", f"c_s = {mat.c_s:.6g}, c_l = {mat.c_l:.6g}  (unit: {mat.velocity_unit})"),
        _line("Rayleigh speed", f"c_r = {mat.c_r:.6g} = {mat.c_r / mat.c_s:.5f} c_s (classical root, used for units)"),
        _line("surface wave", f"{mat.c_surface_born:.6g} = {mat.c_surface_born / mat.c_s:.5f} c_s "
                              "(the Born lattice's own: k_t resists rotation)"),
        _line("stability", f"omega_max = {st.omega_max:.6g} ({_how(st.omega_method)}): dt < "
                           f"{'sqrt(beta^2 + (2/omega_max)^2) - beta' if st.damping.rated else '2/omega_max'} = "
                           f"{st.dt_limit:.6g}  |  paper's dt < a/c_l = {st.dt_paper:.6g}"
                           + (" (not enough here)" if st.dt_paper >= st.dt_limit else "")),
        _line("time step", f"dt = {st.dt:.6g} a/c ({st.dt / st.dt_limit:.3f} of the limit"
                           + (", time.dt" if s["time.dt"] > 0 else f", time.safety = {s['time.safety']:g}") + ")"),
        _line("steps", f"ramp {st.n_ramp} + settle {st.n_settle} + drive {st.n_drive} = {st.n_steps}"
                       f"  (l/c_r = {st.t_unit / st.dt:.1f} steps; ramp {s['load.ramp']:g}, settle "
                       f"{s['load.settle']:g}, drive {s['drive.duration']:g} l/c_r)"),
    ]


def _cost_lines(st, ranks: int) -> list[str]:
    """Node updates and wall time, memory per rank, output size and the usable rank counts."""
    from ..io.output import hdf5_mode
    from ..scene.memory import BASE, available_bytes, predict
    n = st.lattice.n_nodes
    ups = budget.node_updates(st)
    rate = budget.THROUGHPUT[st.precision]
    out = [_line("cost", f"{ups:.4g} node-updates ({n} nodes x {st.n_steps} steps): about "
                         f"{_duration(budget.wall_seconds(st, ranks))} of time loop on {ranks} rank(s) at "
                         f"{rate / 1e6:.0f} M node-updates/s per rank ({st.precision}, measured by parslip bench)")]
    # The writer this Python's h5py would use at this rank count (io.output.hdf5_mode): the gathering
    # writer's rank 0 holds every node's snapshot fields, the collective one spreads them.
    writer = hdf5_mode(ranks)
    mem = predict(st, ranks, gather=writer == "gather")
    have = available_bytes()
    big = max(range(ranks), key=lambda r: mem["per_rank"][r])
    out.append(_line("memory", f"{_mib(mem['per_rank'][big])} on the largest rank (rank {big}), "
                               f"{_mib(mem['total'])} in all on {ranks} rank(s): {mem['bytes_per_node']:.0f} B "
                               f"per node beyond {_mib(BASE)} of process per rank (writer: {writer})"
                               + (f"; more than the {_mib(have)} this host has available: `parslip run` refuses it "
                                  f"here" if have is not None and mem["per_rank"][big] > have else "")))
    ob = budget.output_bytes(st)
    out.append(_line("output", f"{st.n_frames} interface frames (every {st.frame_every} steps) {_mib(ob['interface'])}"
                               f" + {st.n_snapshots} snapshots {_mib(ob['snapshots'])} = {_mib(ob['total'])} "
                               f"of data"))
    r = st.reach
    if r.drift is None:
        halo = (f"fixed interface halos of {max(r.top)} and {max(r.bottom)} columns serve a slip reach of "
                f"{st.slip_reach:.3g} a, across as many slabs as needed")
    else:
        halo = (f"interface halos of {max(r.top)} and {max(r.bottom)} columns at the start follow the slip: the "
                f"block's slabs move with it, its halos reach {st.skin[1]:.3g} a beyond it ahead and "
                f"{st.skin[0]:.3g} a behind")
    out.append(_line("ranks", f"1 to {st.max_ranks()} (slabs of whole columns; {halo})"))
    if ranks > 1:
        m = scaling_figures(st, ranks, writer)
        out.append(_line("scaling", f"per step on the busiest rank over the whole travel: {m['step_us_compute']:.1f} "
                                    f"us of compute, {m['step_us_predicted']:.1f} us predicted (efficiency "
                                    f"{m['efficiency_predicted']:.2f}); {m['peers_max']} peers, "
                                    f"{m['halo_values_per_step']} halo values, {m['foreign_sites_max']} interface "
                                    f"sites beyond its own; rank 0's memory {m['rank0_memory_ratio']:.2f} x the "
                                    f"median rank's ({m['coefficients']})"))
    return out


def scaling_figures(st, ranks: int, writer: str) -> dict:
    """The scaling model's figures (``studies.bench.scaling.travel_model``) with this host's measured
    coefficients where `parslip bench` stored them, else the defaults."""
    from ..studies.bench.scaling import travel_model, coefficients
    return travel_model(st, ranks, coefficients(st.precision), gather=writer == "gather")


def _preset_lines(st, scene_path: str, sets) -> list[str]:
    """The command that runs the scene as each preset, when the scene differs from it."""
    out = []
    for name, preset in (("quick look", presets.QUICK_LOOK), ("publication", presets.PUBLICATION)):
        diff = presets.differences(st.scene, preset)
        if diff:            # README "Error against run time": what each costs and how far it is off
            changed = {x.split("=", 1)[0] for x in diff}      # the preset's value replaces the user's
            keep = [x for x in sets if x.split("=", 1)[0].strip() not in changed]
            extra = "".join(f" --set {x}" for x in keep + diff)
            out.append(_line(name, f"parslip run {scene_path}{extra}"))
    return out


def report(st, scene_path: str, ranks: int = 1, sets: list[str] = ()) -> list[str]:
    """The lines of `parslip info` for the derived scene ``st`` on ``ranks`` ranks."""
    out = _lattice_lines(st, scene_path)
    if st.lattice.has_interface:
        out += _interface_lines(st)
    out += _drive_lines(st) + _time_lines(st) + _cost_lines(st, ranks)
    out += _block("left out", [f"{item}: {text}" for item, text in budget.left_out(st, ranks)])
    out += _block("warnings", advice.warnings(st))
    return out + _preset_lines(st, scene_path, sets)


def _how(method: str) -> str:
    if method == "lanczos":
        return "lanczos: largest eigenvalue of the assembled stiffness, interface springs included"
    if method == "bound":
        return "bound: infinite-lattice maximum + 2 max(k_x, k_y), a rigorous upper bound"
    return method


def cmd_info(args) -> int:
    from ..scene.derive import derive
    scene = load(args.scene, args.set)
    st = derive(scene)
    ranks = args.ranks
    if not 1 <= ranks <= st.max_ranks():
        raise ConfigError(f"--ranks {ranks}: accepted: 1 to {st.max_ranks()} (every rank owns a column of the "
                          f"lattice)")
    if args.json:
        import json
        from ..io.output import hdf5_mode
        from ..analysis.rupture import law_scales
        fig = scaling_figures(st, ranks, hdf5_mode(ranks))
        # The law's scales (tau_p, tau_r, Gamma in rho c_r^2 and m c_r^2/a, D_c, Lambda in a) and, where a
        # prestress is held, tau_0, Andrews' S and L_c (a); NaN as null.
        law = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in law_scales(st).items()
               if k in ("tau_p", "tau_r", "D_c", "Gamma", "Lambda", "tau_0", "S", "L_c")}
        print(json.dumps({"scene": args.scene, "nodes": st.lattice.n_nodes, "dt": st.dt, "steps": st.n_steps,
                          **fig, **law}))
        return 0
    print("\n".join(report(st, args.scene, ranks, args.set)))
    return 0
