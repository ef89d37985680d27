"""Writes the Gmsh-made plate meshes of tests/fem_gmsh_formats.rs (run with the `gmsh` Python
package, 4.15.2 was used): a 1 m x 1 m plate of 16 x 16 transfinite quadrangles with physical
curves "x_edges" (x = 0, 1) and "y_edges" (y = 0, 1), the surface in two physical groups
("plate" and "all": MSH 2.2 then writes each quadrangle twice) and an embedded physical point
"centre", saved as MSH 4.1 ASCII, MSH 4.1 binary and MSH 2.2 ASCII."""
import gmsh

N = 16
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("plate")
geo = gmsh.model.geo
p = [geo.addPoint(x, y, 0) for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)]]
c = [geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
s = geo.addPlaneSurface([geo.addCurveLoop(c)])
centre = geo.addPoint(0.5, 0.5, 0)
geo.synchronize()
gmsh.model.mesh.embed(0, [centre], 2, s)
for ci in c:
    gmsh.model.mesh.setTransfiniteCurve(ci, N + 1)
gmsh.model.mesh.setTransfiniteSurface(s)
gmsh.model.mesh.setRecombine(2, s)
gmsh.model.addPhysicalGroup(1, [c[1], c[3]], name="x_edges")
gmsh.model.addPhysicalGroup(1, [c[0], c[2]], name="y_edges")
gmsh.model.addPhysicalGroup(2, [s], name="plate")
gmsh.model.addPhysicalGroup(2, [s], name="all")
gmsh.model.addPhysicalGroup(0, [centre], name="centre")
gmsh.model.mesh.generate(2)
for version, binary, name in [(4.1, 0, "a41"), (4.1, 1, "b41"), (2.2, 0, "a22")]:
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", binary)
    gmsh.write(f"gmsh_plate_{name}.msh")
gmsh.finalize()
