#!/usr/bin/env python3
"""Writes ccx_cantilever.inp: a steel cantilever (L = 1 m along x, b = 0.04 m in y, h = 0.02 m
in z) of 20-node bricks (C3D20, 40 x 1 x 1), clamped at x = 0, Poisson ratio 0 (so that
Euler-Bernoulli beam theory is the closed form), first 6 modes, nodal displacements to the
.frd. Run: python3 gen_cantilever.py && ccx ccx_cantilever (CalculiX 2.20, Debian calculix-ccx).

Full integration (C3D20), not C3D20R: with one reduced-integration element across the section,
ccx's mid-edge nodes carry spurious (hourglass) displacements of 40 % of the tip value while the
frequencies stay right. Mesh convergence (z-bending frequencies, this mesh against 40 x 2 x 2):
0.003 %, 0.02 %, 0.05 %, 0.09 % for the first four."""
L, B, H = 1.0, 0.04, 0.02
NX, NY, NZ = 40, 1, 1
nodes = {}
def nid(i, j, k):
    return nodes[(i, j, k)]
n = 0
lines = ["*HEADING", "meid test: cantilever beam of C3D20 bricks, closed form Euler-Bernoulli", "*NODE, NSET=NALL"]
for k in range(2 * NZ + 1):
    for j in range(2 * NY + 1):
        for i in range(2 * NX + 1):
            if (i % 2) + (j % 2) + (k % 2) > 1:
                continue
            n += 1
            nodes[(i, j, k)] = n
            lines.append(f"{n}, {L * i / (2 * NX):.10g}, {B * j / (2 * NY):.10g}, {H * k / (2 * NZ):.10g}")
lines.append("*ELEMENT, TYPE=C3D20, ELSET=EALL")
# C3D20 local node order: corners (-,-,-) (+,-,-) (+,+,-) (-,+,-) then z+, mid-edges of the
# z- face, of the z+ face, then the vertical mid-edges.
corner = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2)]
mid = [(1, 0, 0), (2, 1, 0), (1, 2, 0), (0, 1, 0), (1, 0, 2), (2, 1, 2), (1, 2, 2), (0, 1, 2),
       (0, 0, 1), (2, 0, 1), (2, 2, 1), (0, 2, 1)]
e = 0
for k in range(NZ):
    for j in range(NY):
        for i in range(NX):
            e += 1
            ids = [nid(2 * i + a, 2 * j + b, 2 * k + c) for (a, b, c) in corner + mid]
            lines.append(f"{e}, " + ", ".join(str(x) for x in ids[:15]) + ",")
            lines.append(", ".join(str(x) for x in ids[15:]))
lines.append("*NSET, NSET=CLAMP")
clamp = [v for (i, j, k), v in sorted(nodes.items(), key=lambda t: t[1]) if i == 0]
for c in range(0, len(clamp), 16):
    lines.append(", ".join(str(x) for x in clamp[c:c + 16]))
lines += [
    "*BOUNDARY", "CLAMP, 1, 3",
    "*MATERIAL, NAME=STEEL", "*ELASTIC", "2.1e11, 0.0", "*DENSITY", "7850.",
    "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
    "*STEP", "*FREQUENCY", "6", "*NODE FILE", "U", "*END STEP",
]
open("ccx_cantilever.inp", "w").write("\n".join(lines) + "\n")
# The nodes a test uses: tip and mid-span, on the bottom edge's middle (y = b/2, z = 0).
print("tip node", nid(2 * NX, 1, 0), "mid-span node", nid(NX, 1, 0), "nodes", n)
