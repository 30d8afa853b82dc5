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
import numpy as np  # noqa: E402

pl = pv.Plotter(off_screen=True, window_size=(1600, 500))
vals = np.asarray(mesh.point_data[a.field])
lim = float(np.percentile(np.abs(vals), 99)) or 1.0
pl.add_mesh(mesh, scalars=a.field, cmap="coolwarm", clim=(-lim, lim) if vals.ndim == 1 else None, line_width=2)
intact = mesh.extract_cells((mesh.cell_data["interface"] == 1) & (mesh.cell_data["intact"] == 1))
if intact.n_cells:
    pl.add_mesh(intact, color="red", line_width=3)
pl.view_xy()
iface = mesh.extract_cells(mesh.cell_data["interface"] == 1)
if iface.n_cells:                       # frame the contact, not the whole substrate
    b = list(iface.bounds)
    w = b[1] - b[0]
    pl.reset_camera(bounds=[b[0] - 0.1 * w, b[1] + 0.1 * w, b[2] - 0.15 * w, b[3] + 0.15 * w, 0, 0])
png = a.png or os.path.splitext(a.h5)[0] + f"_{a.field}_{k}.png"
pl.screenshot(png)
print(png, f"(step {k} of {n}, t = {r.reader.GetTimeValue():.3f} l/c_r)")
