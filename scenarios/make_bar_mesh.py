#!/usr/bin/env python3
"""Writes scenarios/bar.mesh (medit, metres) for bar_tear.json: a bar of
12 x 3 x 3 cubes of 5 mm (0.06 x 0.015 x 0.015 m, 208 points, 648 tets),
each cube cut into 6 positively oriented tets along its main diagonal.
Run from this folder: python3 make_bar_mesh.py."""
import itertools

NX, NY, NZ, H = 12, 3, 3, 0.005

def index(i, j, k):
    return i + (NX + 1) * (j + (NY + 1) * k)

def signed_volume(p, t):
    a, b, c, d = (p[i] for i in t)
    u, v, w = ([q[n] - a[n] for n in range(3)] for q in (b, c, d))
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6

points = [(i * H, j * H, k * H) for k in range(NZ + 1) for j in range(NY + 1) for i in range(NX + 1)]
tets = []
for i, j, k in itertools.product(range(NX), range(NY), range(NZ)):
    corner = lambda bits: index(i + (bits & 1), j + ((bits >> 1) & 1), k + ((bits >> 2) & 1))
    for axes in itertools.permutations(range(3)):
        bits, tet = 0, [corner(0)]
        for axis in axes:  # a monotone path from corner 000 to corner 111
            bits |= 1 << axis
            tet.append(corner(bits))
        if signed_volume(points, tet) < 0:
            tet[1], tet[2] = tet[2], tet[1]
        tets.append(tet)

with open("bar.mesh", "w") as f:
    f.write("MeshVersionFormatted 1\nDimension 3\nVertices\n%d\n" % len(points))
    for x, y, z in points:
        f.write("%.9g %.9g %.9g 0\n" % (x, y, z))
    f.write("Tetrahedra\n%d\n" % len(tets))
    for t in tets:
        f.write("%d %d %d %d 0\n" % tuple(n + 1 for n in t))
    f.write("End\n")
