#!/usr/bin/env python3
"""Writes the small tet meshes of the stress suite (medit .mesh, metres).
Run from this folder: python3 make_meshes.py. Kuhn-subdivided boxes (6 tets
per cube), each tet oriented positively unless a case inverts it on purpose."""
import itertools

def box(n, size, z0=0.0):
    h = size / n
    pts = [(i * h, j * h, z0 + k * h) for k in range(n + 1) for j in range(n + 1) for i in range(n + 1)]
    idx = lambda i, j, k: i + (n + 1) * (j + (n + 1) * k)
    tets = []
    for i, j, k in itertools.product(range(n), repeat=3):
        c = [idx(i + (v & 1), j + ((v >> 1) & 1), k + ((v >> 2) & 1)) for v in range(8)]
        for perm in itertools.permutations(range(3)):
            v, path = 0, [c[0]]
            for axis in perm:
                v |= 1 << axis
                path.append(c[v])
            tets.append(path)
    return pts, [orient(pts, t) for t in tets]

def vol(p, t):
    a, b, c, d = (p[i] for i in t)
    u = [b[i] - a[i] for i in range(3)]; v = [c[i] - a[i] for i in range(3)]; w = [d[i] - a[i] for i in range(3)]
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6

def orient(p, t):
    return t if vol(p, t) > 0 else [t[0], t[2], t[1], t[3]]

def write(name, pts, tets):
    with open(name, "w") as f:
        f.write("MeshVersionFormatted 1\nDimension 3\nVertices\n%d\n" % len(pts))
        for x, y, z in pts:
            f.write("%.9g %.9g %.9g 0\n" % (x, y, z))
        f.write("Tetrahedra\n%d\n" % len(tets))
        for t in tets:
            f.write("%d %d %d %d 0\n" % tuple(i + 1 for i in t))
        f.write("End\n")

# 4 x 4 x 4 cubes of 1 cm: 125 points, 384 tets.
pts, tets = box(4, 0.04)
write("box.mesh", pts, tets)

# One tet turned inside out (two vertices swapped).
bad = [list(t) for t in tets]
bad[17] = [bad[17][0], bad[17][2], bad[17][1], bad[17][3]]
write("inverted.mesh", pts, bad)

# Two boxes stacked with their interface points duplicated (coincident, not
# connected): 250 points, 50 pairs of coincident points.
top_pts, top_tets = box(4, 0.04, 0.04)
off = len(pts)
write("coincident.mesh", pts + top_pts, tets + [[i + off for i in t] for t in top_tets])

# A near-flat tet: an interior point moved almost onto a neighbour's plane
# (volume ~1e-3 of its neighbours', above the loader's 1e-9 L^3 zero test).
flat = list(pts)
i = 1 + 5 * (1 + 5 * 1)  # lattice point (1,1,1)
x, y, z = flat[i]
flat[i] = (x + 0.0099, y, z)
write("near_flat.mesh", flat, tets)
