"""Opens the XDMF sidecar of a run on a triangular background mesh (H5Writer::set_mesh) with ParaView's default
reader and checks that every time step shows the mesh beside the particles: one block of triangles (the mesh,
with the expected number of cells) and one of vertices (the particles, with the expected number of points at the
last time step), the particles inside the mesh.

Usage (under xvfb-run, with absolute paths: pvpython resolves relative ones elsewhere):
  pvpython check_paraview_mesh.py FILE.xdmf TRIANGLES PARTICLES
e.g. from check_paraview.sh: xvfb-run -a pvpython "$here/check_paraview_mesh.py" "$work/run.xdmf" 32 "$n"
"""
import sys

from paraview.simple import OpenDataFile, servermanager
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import VTK_POLY_VERTEX, VTK_TRIANGLE, VTK_VERTEX

path, triangles, particles = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
reader = OpenDataFile(path)
assert reader is not None, f"ParaView cannot read {path}"
assert reader.GetXMLName() == "Xdmf3ReaderS", f"default reader is {reader.GetXMLName()}"
times = list(reader.TimestepValues) or [0.0]


def blocks_at(time):
    """The leaf blocks of one time step's spatial collection, by their cell types: "mesh" and "particles"."""
    reader.UpdatePipeline(time)
    data = servermanager.Fetch(reader)
    # the fetched blocks carry no names, so the cells tell them apart: triangles for the mesh, vertices otherwise
    found = {}
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        block = it.GetCurrentDataObject()
        assert block.GetClassName() == "vtkUnstructuredGrid", f"t = {time}: a {block.GetClassName()} block"
        types = set(vtk_to_numpy(block.GetCellTypesArray()).tolist()) if block.GetNumberOfCells() else set()
        if types == {VTK_TRIANGLE}:
            kind = "mesh"
        elif types <= {VTK_POLY_VERTEX, VTK_VERTEX} and types:
            kind = "particles"
        else:
            raise AssertionError(f"t = {time}: a block with cell types {sorted(types)}")
        assert kind not in found, f"t = {time}: two {kind} blocks"
        found[kind] = block
        it.GoToNextItem()
    assert sorted(found) == ["mesh", "particles"], f"t = {time}: blocks {sorted(found)}"
    return found


for time in times:  # the mesh is in every time step: ParaView shows it whichever step is selected
    mesh = blocks_at(time)["mesh"]
    cells = mesh.GetNumberOfCells()
    assert cells == triangles, f"t = {time}: {cells} triangles, expected {triangles}"
    z = mesh.GetBounds()[4:]
    assert z == (0.0, 0.0), f"t = {time}: mesh z range {z}, expected the plane z = 0"

last = blocks_at(times[-1])  # the particles as check_paraview.py checks them: at the last time step
cloud, mesh = last["particles"], last["mesh"]
assert cloud.GetNumberOfPoints() == particles, f"{cloud.GetNumberOfPoints()} points, expected {particles}"
inside, around = cloud.GetBounds(), mesh.GetBounds()
assert all(around[2 * d] <= inside[2 * d] and inside[2 * d + 1] <= around[2 * d + 1] for d in range(3)), \
    f"particles {inside} outside the mesh {around}"
print(f"{path}: {triangles} triangles on {mesh.GetNumberOfPoints()} nodes in each of {len(times)} time steps, "
      f"{particles} particles")
