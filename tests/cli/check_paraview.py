"""Opens an mpm XDMF sidecar with ParaView's default reader and checks what a user looks for: the particles, the
velocity and displacement vectors, the stress and F tensors, and the background grid around them, at the last time
step.

Usage (under xvfb-run): pvpython check_paraview.py FILE.xdmf PARTICLES GRID_NODES
"""
import sys

from paraview.simple import OpenDataFile, servermanager

path, particles, grid_nodes = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
reader = OpenDataFile(path)
assert reader is not None, f"ParaView cannot read {path}"
assert reader.GetXMLName() == "Xdmf3ReaderS", f"default reader is {reader.GetXMLName()}"
times = reader.TimestepValues
reader.UpdatePipeline(times[-1] if times else 0.0)
data = servermanager.Fetch(reader)
# each time step is a spatial collection: a multiblock of the particles and the grid
blocks = []
it = data.NewIterator()
it.InitTraversal()
while not it.IsDoneWithTraversal():
    blocks.append(it.GetCurrentDataObject())
    it.GoToNextItem()
by_type = {b.GetClassName(): b for b in blocks}
assert sorted(by_type) == ["vtkRectilinearGrid", "vtkUnstructuredGrid"], f"blocks {sorted(by_type)}"
cloud, grid = by_type["vtkUnstructuredGrid"], by_type["vtkRectilinearGrid"]
assert cloud.GetNumberOfPoints() == particles, f"{cloud.GetNumberOfPoints()} points, expected {particles}"
assert grid.GetNumberOfPoints() == grid_nodes, f"{grid.GetNumberOfPoints()} grid nodes, expected {grid_nodes}"
inside, around = cloud.GetBounds(), grid.GetBounds()
assert all(around[2 * d] <= inside[2 * d] and inside[2 * d + 1] <= around[2 * d + 1] for d in range(3)), \
    f"particles {inside} outside the grid {around}"
arrays = {cloud.GetPointData().GetArray(i).GetName(): cloud.GetPointData().GetArray(i)
          for i in range(cloud.GetPointData().GetNumberOfArrays())}
for name, components in (("velocity", 3), ("displacement", 3), ("stress", 9), ("F", 9)):
    assert name in arrays, f"no {name} array: {sorted(arrays)}"
    assert arrays[name].GetNumberOfComponents() == components, f"{name}: {arrays[name].GetNumberOfComponents()}"
    assert arrays[name].GetRange(-1)[1] > 0.0, f"{name} is zero everywhere"
print(f"{path}: {particles} particles, {grid_nodes} grid nodes, {len(times)} time steps, arrays {sorted(arrays)}")
