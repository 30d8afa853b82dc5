"""Each rule written once: the drive and the damping read from the scene only by their homes in ``model``,
the event kinds numbered in one module, and the bond table's rows described in one table from which the
exchange, the checkpoint and the output take theirs."""
import ast
import re
import sys
import textwrap
from pathlib import Path

import numpy as np

from helpers import REPO, cli_env, require, run_limited, WHEEL_MPIEXEC

PACKAGE = REPO / "parslip"

# Keys only ``model.drive.Drive`` and ``model.damping.Damping`` read from a scene dict.
HOMED = re.compile(r"^(drive\.|time\.zeta$|time\.damping$)")


def _raw_reads(source: str) -> list[str]:
    """Keys matching HOMED read from a mapping in ``source``: a subscript or a ``.get`` by a string constant."""
    out = []
    for node in ast.walk(ast.parse(source)):
        key = None
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
            key = node.slice.value
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get"
              and node.args and isinstance(node.args[0], ast.Constant)):
            key = node.args[0].value
        if isinstance(key, str) and HOMED.match(key):
            out.append(f"{key} (line {node.lineno})")
    return out


def test_no_drive_or_damping_key_is_read_raw_on_the_run_path():
    """engine/, parallel/, io/ and the scene's derived quantities ask ``setup.drive`` and ``setup.damping``;
    the check itself finds both forms of a raw read."""
    assert _raw_reads('v = sc["drive.mode"]; z = s.get("time.zeta", 0)') == ["drive.mode (line 1)",
                                                                              "time.zeta (line 1)"]
    files = [p for sub in ("engine", "parallel", "io") for p in sorted((PACKAGE / sub).rglob("*.py"))]
    files += [PACKAGE / "scene" / "derive.py", PACKAGE / "scene" / "memory.py"]
    found = {str(p.relative_to(REPO)): r for p in files if (r := _raw_reads(p.read_text()))}
    assert found == {}


def _kind_numbers(source: str) -> list[int]:
    """Lines of ``source`` that number an event kind: an assignment of an integer to a name ending in
    BREAK or FORM, or a comparison of a ``["kind"]`` (or ``kind``/``kinds``) with an integer."""
    lines = []
    named = re.compile(r"(^|_)(BREAK|FORM)$")
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names = [n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)]
            ints = [n for n in ast.walk(node.value) if isinstance(n, ast.Constant) and type(n.value) is int]
            if ints and any(named.search(n) for n in names):
                lines.append(node.lineno)
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            kind = any((isinstance(s, ast.Subscript) and isinstance(s.slice, ast.Constant) and s.slice.value == "kind")
                       or (isinstance(s, ast.Name) and s.id in ("kind", "kinds")) for s in sides)
            if kind and any(isinstance(s, ast.Constant) and type(s.value) is int for s in sides):
                lines.append(node.lineno)
    return lines


def test_event_kinds_are_numbered_in_one_module():
    """Only ``model.interface`` writes the event kinds as integers; the engine, the contract, the front
    catalogue and postprocess/ import them (the check finds each form it looks for)."""
    assert _kind_numbers("BREAK, FORM = 1, 2\nEVENT_FORM = 2\nn = ev['kind'] == 2\nBREAKS = 0") == [1, 2, 3]
    files = sorted(PACKAGE.rglob("*.py")) + sorted((REPO / "postprocess").rglob("*.py"))
    found = sorted(str(p.relative_to(REPO)) for p in files if _kind_numbers(p.read_text()))
    assert found == ["parslip/model/interface.py"]
    from parslip.engine.kernels import interface as ik
    from parslip.io import contract
    from parslip.model import interface as law
    assert (ik.BREAK, ik.FORM) == (contract.EVENT_BREAK, contract.EVENT_FORM) == (law.BREAK, law.FORM)
    assert set(law.EVENT_KINDS) == {law.BREAK, law.FORM}


def test_the_bond_table_implies_the_exchange_the_checkpoint_and_the_output():
    """Every structure that lists bond rows is the table's: the index constants, the travelling rows, the
    checkpoint's datasets and dtypes, the contract's per-frame and per-site fields."""
    from parslip.io import checkpoint, contract
    from parslip.model import interface as law
    names = [r.name for r in law.BOND_TABLE]
    rows = ("partner", "x0", "cand", "clock", "kx", "ky", "delta_b", "softening", "peak", "slipped", "spent",
            "stick")
    assert [law.PARTNER, law.X0, law.CAND, law.CLOCK, law.KX, law.KY, law.DELTA_B, law.SOFTENING, law.PEAK,
            law.SLIPPED, law.SPENT, law.STICK] == [names.index(n) for n in rows]
    assert law.BONDS.travel == (law.PARTNER, law.X0, law.CAND, law.CLOCK, law.PEAK, law.SLIPPED, law.SPENT,
                                law.STICK)
    assert checkpoint.DATASETS[-len(names):] == tuple(names)
    assert law.BONDS.dtypes == {"partner": "int64", "x0": None, "cand": "int64", "clock": "int64", "kx": None,
                                "ky": None, "delta_b": None, "softening": None, "peak": None, "slipped": None,
                                "spent": None, "stick": None}
    assert "partner" in contract.FRAME_FIELDS and contract.SITE_DATASETS == ("x", "kx", "ky", "delta_b", "softening")
    drawn = law.bond_layout(law.BOND_TABLE + (law.BondRow("drawn", True, None, "site", "a", "drawn"),))
    assert drawn.travel == law.BONDS.travel + (len(names),) and drawn.checkpoint[-1] == "drawn"
    assert drawn.site_output[-1] == "drawn"


# Run on 2 ranks: the bond table gets one more row, "drawn", that travels and is checkpointed; no kernel
# writes it, so the script writes f(site) into each rank's OWNED sites and a marker into its HALO copies.
DRAWN_SCRIPT = """
import sys
import numpy as np
import parslip.model.interface as law
law.BOND_TABLE = law.BOND_TABLE + (law.BondRow("drawn", True, None, None, "-", "a row drawn for the test"),)
law.BONDS = law.bond_layout(law.BOND_TABLE)          # before anything that reads the table is imported
from mpi4py import MPI
from parslip.engine.simulation import Simulation
from parslip.io import checkpoint
from parslip.scene.derive import derive
from parslip.scene.load import resolve

comm = MPI.COMM_WORLD
SETS = [("lattice.top_rows", 4), ("lattice.top_cols", 24), ("lattice.bottom_rows", 4),
        ("lattice.bottom_cols", 40), ("load.ramp", 0.1), ("load.settle", 0.1), ("drive.v0", 0.02),
        ("drive.duration", 1.0), ("output.snapshots", 0), ("interface.heal_time", 0.3)]
setup = derive(resolve({}, SETS))
row = law.BONDS.names.index("drawn")
f = lambda site: 0.25 + 1.5 * site                  # noqa: E731
sim = Simulation(setup, comm=comm)
sim.run(until=50)
s = sim.state
g = s.iface.geom
local = np.arange(g.tlo, g.thi)                      # every stored site: OWNED and HALO
site = local + g.tbase - setup.lattice.top.col0
own = (local >= g.town0) & (local < g.town1)
s.iface.bonds[row, g.tlo:g.thi] = np.where(own, f(site), -7.0)
sim.run(until=51)                                    # one step: one exchange
halo = s.iface.bonds[row, g.tlo:g.thi][~own]
assert (~own).sum() > 0 and np.array_equal(halo, f(site[~own])), "the drawn row did not travel"
path = sys.argv[1]
checkpoint.write(comm, path, sim.checkpoint_slab(), sim.checkpoint_attrs(), sim.checkpoint_table())
whole, attrs = checkpoint.read(path, (0, setup.lattice.n_nodes), (0, setup.lattice.n_top_sites))
assert np.array_equal(whole.arrays["drawn"], f(np.arange(setup.lattice.n_top_sites))), "the checkpoint lost the row"
again = Simulation(setup, comm=comm)
again.restore(*checkpoint.read(path, *again.slab_ranges()))
t = again.state
assert np.array_equal(t.iface.bonds[row, g.tlo:g.thi], f(site)), "the restart did not restore the row"
for name in law.BONDS.names:
    assert np.array_equal(t.owned_bonds()[name], s.owned_bonds()[name]), name
sim.run(until=120)
again.run(until=120)
assert np.array_equal(again.u, sim.u) and np.array_equal(t.iface.bonds, s.iface.bonds), "the restart diverged"
ranks = comm.gather(comm.Get_rank(), root=0)      # one line, from rank 0: two ranks' prints can interleave
if comm.Get_rank() == 0:
    print("drawn row ok on ranks", *ranks, flush=True)
"""


def test_a_drawn_bond_row_travels_checkpoints_and_restarts(tmp_path):
    """One line added to the table (monkeypatched before the engine is imported) is enough: on 2 ranks
    the row's HALO copies receive the owner's values, the checkpoint holds it by site, a restart puts it
    back (HALO copies included) and continues bitwise as the run that was not interrupted."""
    require("gather")
    script = tmp_path / "drawn.py"
    script.write_text(textwrap.dedent(DRAWN_SCRIPT))
    p = run_limited([WHEEL_MPIEXEC, "-n", "2", sys.executable, str(script), str(tmp_path / "c.ckpt.h5")],
                    env=cli_env(), timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    assert "drawn row ok on ranks 0 1" in p.stdout, p.stdout[-2000:]
