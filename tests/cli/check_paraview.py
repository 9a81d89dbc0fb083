"""Opens an mpm XDMF sidecar with ParaView's default reader and checks what a user looks for: the particles, the
velocity and displacement vectors, the stress and F tensors, at the last time step.

Usage (under xvfb-run): pvpython check_paraview.py FILE.xdmf PARTICLES
"""
import sys

from paraview.simple import OpenDataFile, servermanager

path, particles = sys.argv[1], int(sys.argv[2])
reader = OpenDataFile(path)
assert reader is not None, f"ParaView cannot read {path}"
assert reader.GetXMLName() == "Xdmf3ReaderS", f"default reader is {reader.GetXMLName()}"
times = reader.TimestepValues
reader.UpdatePipeline(times[-1] if times else 0.0)
data = servermanager.Fetch(reader)
assert data.GetNumberOfPoints() == particles, f"{data.GetNumberOfPoints()} points, expected {particles}"
arrays = {data.GetPointData().GetArray(i).GetName(): data.GetPointData().GetArray(i)
          for i in range(data.GetPointData().GetNumberOfArrays())}
for name, components in (("velocity", 3), ("displacement", 3), ("stress", 9), ("F", 9)):
    assert name in arrays, f"no {name} array: {sorted(arrays)}"
    assert arrays[name].GetNumberOfComponents() == components, f"{name}: {arrays[name].GetNumberOfComponents()}"
    assert arrays[name].GetRange(-1)[1] > 0.0, f"{name} is zero everywhere"
print(f"{path}: {particles} particles, {len(times)} time steps, arrays {sorted(arrays)}")
