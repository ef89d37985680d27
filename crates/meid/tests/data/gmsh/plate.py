"""Writes the Gmsh-made plate meshes of tests/fem_gmsh_formats.rs (run with the `gmsh` Python
package; 4.15.2 was used): a 1 m x 1 m plate of 16 x 16 transfinite quadrangles made of four
0.5 m squares around the centre point, with physical curves "x_edges" (x = 0, 1) and
"y_edges" (y = 0, 1), the surfaces in two physical groups ("plate" and "all": MSH 2.2 then
writes each quadrangle twice) and the physical point "centre", saved as MSH 4.1 ASCII, MSH 4.1
binary and MSH 2.2 ASCII."""
import gmsh

N = 16  # elements per side
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("plate")
geo = gmsh.model.geo
pt = {(i, j): geo.addPoint(i / 2, j / 2, 0) for i in range(3) for j in range(3)}
line = {}


def edge(a, b):
    if (b, a) in line:
        return -line[(b, a)]
    line[(a, b)] = geo.addLine(pt[a], pt[b])
    return line[(a, b)]


surfaces = []
for i in range(2):
    for j in range(2):
        corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
        loop = [edge(corners[k], corners[(k + 1) % 4]) for k in range(4)]
        surfaces.append(geo.addPlaneSurface([geo.addCurveLoop(loop)]))
geo.synchronize()
for c in line.values():
    gmsh.model.mesh.setTransfiniteCurve(c, N // 2 + 1)
for s in surfaces:
    gmsh.model.mesh.setTransfiniteSurface(s)
    gmsh.model.mesh.setRecombine(2, s)


def boundary(on):
    return [c for (a, b), c in line.items() if on(a) and on(b)]


gmsh.model.addPhysicalGroup(1, boundary(lambda p: p[0] in (0, 2)), name="x_edges")
gmsh.model.addPhysicalGroup(1, boundary(lambda p: p[1] in (0, 2)), name="y_edges")
gmsh.model.addPhysicalGroup(2, surfaces, name="plate")
gmsh.model.addPhysicalGroup(2, surfaces, name="all")
gmsh.model.addPhysicalGroup(0, [pt[(1, 1)]], name="centre")
gmsh.model.mesh.generate(2)
for version, binary, name in [(4.1, 0, "a41"), (4.1, 1, "b41"), (2.2, 0, "a22")]:
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", binary)
    gmsh.write(f"gmsh_plate_{name}.msh")
gmsh.finalize()
