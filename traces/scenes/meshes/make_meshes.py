#!/usr/bin/env python3
"""Writes the hand-built meshes of the failure scenes (run from anywhere; the OBJ files are
committed beside this script, which documents and regenerates them):

broken.obj   bad input as real exporters leave it: a grid with T-junctions (every other
             column split at mid-height, so a vertex lies on its neighbour's edge), a
             non-manifold fin (three faces on one edge), a duplicated face (an exact
             coplanar tie), zero-area faces (collinear corners, a repeated corner) and a
             face with the opposite winding.
needles.obj  slivers and needles: a fan of 240 long triangles a fraction of a degree wide,
             and a strip of 100 triangles one hundredth of their length high.
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def write(name, header, verts, faces):
    with open(os.path.join(HERE, name), "w") as f:
        f.write("# " + header + " (written by make_meshes.py)\n")
        for v in verts:
            f.write("v %.6f %.6f %.6f\n" % v)
        for t in faces:
            f.write("f %d %d %d\n" % tuple(i + 1 for i in t))


def broken():
    verts, faces = [], []

    def vid(p):
        verts.append(p)
        return len(verts) - 1

    # Grid of 6 x 6 quads on z = 0 over [-1, 1]^2; odd columns split at every mid-height.
    n = 6
    cols = {}
    for i in range(n + 1):
        for j in range(2 * n + 1):
            if j % 2 == 1 and not (i % 2 == 1 or (i > 0 and (i - 1) % 2 == 1)):
                continue
            cols[(i, j)] = vid((-1 + 2 * i / n, -1 + 2 * j / (2 * n), 0.0))
    for i in range(n):
        split = i % 2 == 1
        for j in range(n):
            a, b = cols[(i, 2 * j)], cols[(i + 1, 2 * j)]
            c, d = cols[(i + 1, 2 * j + 2)], cols[(i, 2 * j + 2)]
            if split:
                m0, m1 = cols[(i, 2 * j + 1)], cols[(i + 1, 2 * j + 1)]
                faces += [(a, b, m1), (a, m1, m0), (m0, m1, c), (m0, c, d)]
            else:
                faces += [(a, b, c), (a, c, d)]
    # One face of the grid with the opposite winding.
    faces[7] = (faces[7][0], faces[7][2], faces[7][1])
    # A non-manifold fin: three faces on the edge from (0, 0, 0) to (0, 0.6, 0).
    e0, e1 = vid((0.0, 0.0, 0.05)), vid((0.0, 0.6, 0.05))
    for k, ang in enumerate((20.0, 90.0, 160.0)):
        r = math.radians(ang)
        tip = vid((0.35 * math.cos(r), 0.3, 0.05 + 0.35 * math.sin(r)))
        faces.append((e0, tip, e1) if k != 1 else (e0, e1, tip))
    # A duplicated face floating in front of the grid, and zero-area faces beside it.
    p, q, r = vid((-0.8, 0.5, 0.2)), vid((-0.3, 0.5, 0.2)), vid((-0.55, 0.9, 0.2))
    faces += [(p, q, r), (p, q, r)]
    c0, c1, c2 = vid((0.3, -0.8, 0.1)), vid((0.5, -0.7, 0.1)), vid((0.7, -0.6, 0.1))
    faces += [(c0, c1, c2), (c0, c0, c2)]
    write("broken.obj", "T-junctions, a non-manifold fin, a duplicated face, zero-area and flipped faces",
          verts, faces)


def needles():
    verts, faces = [], []
    # Fan of needles around the origin: long, a fraction of a degree wide.
    verts.append((0.0, 0.0, 0.0))
    count = 240
    for k in range(count):
        a = 2 * math.pi * k / count
        w = math.radians(0.15)
        l = 1.0 + 0.3 * math.sin(5 * a)
        verts.append((l * math.cos(a - w), l * math.sin(a - w), 0.1 * math.sin(3 * a)))
        verts.append((l * math.cos(a + w), l * math.sin(a + w), 0.1 * math.sin(3 * a)))
        faces.append((0, 2 * k + 1, 2 * k + 2))
    # A strip of slivers below the fan: triangles 1/100 of their length high.
    base = len(verts)
    for k in range(101):
        x = -1.0 + 2.0 * k / 100
        verts.append((x, -1.4, 0.0))
        verts.append((x + 0.5, -1.4 + 0.02 * (1 + k % 2), 0.02 * k / 100))
    for k in range(100):
        a, b, c, d = base + 2 * k, base + 2 * k + 2, base + 2 * k + 3, base + 2 * k + 1
        faces += [(a, b, c), (a, c, d)] if k % 2 == 0 else [(a, b, d)]
    write("needles.obj", "needles and slivers", verts, faces)


if __name__ == "__main__":
    broken()
    needles()
