"""Render one whole-lattice snapshot with pyvista, off screen.

    python postprocess/snapshot.py out/push.vtkhdf --step -1 --field sxy --png sxy.png

Fields: sxx, syy, sxy (in rho c_r^2), velocity.  In ParaView, open the
.vtkhdf file directly; the time steps are the snapshots (t in l/c_r).
"""
import argparse
import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
import pyvista as pv  # noqa: E402

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("h5")
p.add_argument("--step", type=int, default=-1, help="snapshot index, -1 = last")
p.add_argument("--field", default="sxy")
p.add_argument("--png", default=None)
a = p.parse_args()
r = pv.get_reader(a.h5, force_ext=".vtkhdf")
r.reader.UpdateInformation()
n = r.reader.GetNumberOfSteps()
k = a.step % n
r.reader.SetStep(k)
mesh = r.read()
pl = pv.Plotter(off_screen=True, window_size=(1600, 500))
pl.add_mesh(mesh, scalars=a.field, cmap="coolwarm", line_width=2)
intact = mesh.extract_cells((mesh.cell_data["interface"] == 1) & (mesh.cell_data["intact"] == 1))
if intact.n_cells:
    pl.add_mesh(intact, color="red", line_width=3)
pl.view_xy()
png = a.png or os.path.splitext(a.h5)[0] + f"_{a.field}_{k}.png"
pl.screenshot(png)
print(png, f"(step {k} of {n}, t = {r.reader.GetTimeValue():.3f} l/c_r)")
