"""Run by ParaView's own pvpython (not by pytest): what ParaView shows of a file it opens.

    pvpython --dr --no-mpi --force-offscreen-rendering tests/pv_read_xdmf.py RUN.xdmf2

Opens the file as the GUI's File > Open does (``OpenDataFile``: the reader
ParaView's reader factory picks for the extension) and prints one JSON
object: the reader's name, its time steps and, per step, the point and cell
counts, cell types, points, cell offsets and connectivity, point and cell
fields.  Only ParaView's Python (and its numpy) is used here, nothing of parslip.
"""
import json
import sys

from paraview import servermanager as sm
from paraview import simple
from paraview.vtk.util.numpy_support import vtk_to_numpy


def arrays(data):
    return {data.GetArrayName(i): vtk_to_numpy(data.GetArray(i)).tolist() for i in range(data.GetNumberOfArrays())}


def read(path):
    r = simple.OpenDataFile(path)
    r.UpdatePipelineInformation()
    times = [float(t) for t in r.TimestepValues]
    steps = []
    for t in times:
        r.UpdatePipeline(t)
        d = sm.Fetch(r)
        while d.IsA("vtkMultiBlockDataSet"):       # a reader may wrap the grid in blocks
            d = d.GetBlock(0)
        cells = d.GetCells()
        steps.append({
            "class": d.GetClassName(),
            "n_points": d.GetNumberOfPoints(),
            "n_cells": d.GetNumberOfCells(),
            "cell_types": sorted({d.GetCellType(i) for i in range(d.GetNumberOfCells())}),
            "points": vtk_to_numpy(d.GetPoints().GetData()).tolist() if d.GetNumberOfPoints() else [],
            "offsets": vtk_to_numpy(cells.GetOffsetsArray()).tolist() if d.GetNumberOfCells() else [],
            "connectivity": vtk_to_numpy(cells.GetConnectivityArray()).tolist() if d.GetNumberOfCells() else [],
            "point_data": arrays(d.GetPointData()),
            "cell_data": arrays(d.GetCellData()),
        })
    return {"reader": r.GetXMLName(), "times": times, "steps": steps}


print(json.dumps(read(sys.argv[1])))
