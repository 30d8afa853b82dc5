"""One shipped scene, run through the Python API, and the figure it makes.

    python examples/scene_figure.py run/push.toml             # writes examples/figures/push.png
    mpiexec -n 2 python examples/scene_figure.py run/shear_l500.toml
    python examples/scene_figure.py run/pull.toml --quick     # a small, short version (seconds)

The run goes to out/examples/<scene>.vtkhdf (reused when it is complete).  The figure has three panels:
the space-time diagram of the interface bonds with each detected front's tip, the front speeds along the
contact, and mu(t) = -F_T/F_N, the friction the interface mobilises, with the fronts' nucleations marked.
"""
import argparse
import os
import sys

import parslip
from parslip.plot import figures

QUICK = {"lattice.top_rows": 4, "lattice.top_cols": 24, "lattice.bottom_rows": 4, "lattice.bottom_cols": 40,
         "drive.v0": 0.02, "drive.duration": 6.0, "output.snapshots": 0}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", help="a scene file, e.g. run/push.toml")
    p.add_argument("--out", default=os.path.join("out", "examples"), help="folder of the run files")
    p.add_argument("--figures", default=os.path.join(os.path.dirname(__file__), "figures"),
                   help="folder of the figure (default: examples/figures)")
    p.add_argument("--quick", action="store_true", help="a small lattice and a short drive: seconds")
    a = p.parse_args(argv)
    comm = None
    if int(os.environ.get("PMI_SIZE", os.environ.get("OMPI_COMM_WORLD_SIZE", "1"))) > 1:
        from mpi4py import MPI
        comm = MPI.COMM_WORLD
    name = os.path.splitext(os.path.basename(a.scene))[0] + ("_quick" if a.quick else "")
    out = os.path.join(a.out, name + ".vtkhdf")
    run = parslip.run(a.scene, out=out, sets=QUICK if a.quick else None, restart="auto", comm=comm)
    if comm is None or comm.Get_rank() == 0:
        png = draw(run, os.path.join(a.figures, name + ".png"))
        print(png)
    return 0


def draw(run, png: str) -> str:
    plt = figures.pyplot()
    fig, (ax0, ax1, ax2) = plt.subplots(1, 3, figsize=(14, 4.8))
    figures.draw_spacetime(ax0, run.interface)
    fronts = run.fronts()
    for i, f in enumerate(fronts):
        ax0.plot(f.tip["x"], f.tip["t"], color=figures.colour(i), lw=1)
        ax1.plot(f.tip["x"], abs(f.tip["v"]), color=figures.colour(i), lw=1, label=f"front {i + 1}" if i < 4 else None)
    ax0.set_title("interface bonds: intact yellow, broken white", fontsize=9)
    ax1.set_xlabel(r"$x_{tip}/l$")
    ax1.set_ylabel(r"$|v|/c_r$")
    ax1.set_yscale("log")
    ax1.set_title("front speeds", fontsize=9)
    figures.legend(ax1, 7)
    ax2.plot(run.times, run.interface["mu"], color="k", lw=0.8)
    for i, f in enumerate(fronts):
        ax2.axvline(f.nucleation_time, color=figures.colour(i), lw=0.6, ls=":")
    ax2.set_xlabel(r"$t\,c_r/l$")
    ax2.set_ylabel(r"$\mu = -F_T/F_N$")
    ax2.set_title("friction mobilised; dotted: nucleations", fontsize=9)
    fig.suptitle(f"{os.path.basename(run.path)}: {run.mode}, v0/c_r = {run.v0:g}", fontsize=10)
    os.makedirs(os.path.dirname(png) or ".", exist_ok=True)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return png


if __name__ == "__main__":
    sys.exit(main())
