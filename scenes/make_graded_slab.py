#!/usr/bin/env python3
"""Writes scenes/meshes/graded_slab.{node,ele}: the 16x4x16-cube slab of stiff_slab.json
(1.6 x 0.4 x 1.6 m, 1445 vertices, 6144 tets) with its x and z spacings growing
geometrically by 12x from one side to the other, so that tet volumes (and A's diagonal) spread
over two orders of magnitude as in a real tet mesh (issue 17). The mesh origin is the centre of
the bottom face. Usage: /usr/bin/python3 scenes/make_graded_slab.py
"""
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def graded(cells, length, ratio):
    widths = ratio ** (np.arange(cells) / (cells - 1))
    widths = widths / widths.sum() * length
    return np.concatenate([[0.0], np.cumsum(widths)]) - length / 2


def main():
    xs, zs = graded(16, 1.6, 12.0), graded(16, 1.6, 12.0)
    ys = np.linspace(0.0, 0.4, 5)
    ny, nz = len(ys), len(zs)
    points = np.array([(x, y, z) for x in xs for y in ys for z in zs])
    index = lambda i, j, k: (i * ny + j) * nz + k  # noqa: E731
    kuhn = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
    tets = []
    for i in range(len(xs) - 1):
        for j in range(ny - 1):
            for k in range(nz - 1):
                corner = [index(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)) for b in range(8)]
                for t in kuhn:
                    tet = [corner[v] for v in t]
                    a, b, c, d = points[tet]
                    if np.dot(np.cross(b - a, c - a), d - a) < 0:  # positive orientation
                        tet[1], tet[2] = tet[2], tet[1]
                    tets.append(tet)
    out = os.path.join(HERE, "meshes")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "graded_slab.node"), "w") as f:
        f.write(f"{len(points)} 3 0 0\n")
        for n, p in enumerate(points):
            f.write(f"{n} {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n")
    with open(os.path.join(out, "graded_slab.ele"), "w") as f:
        f.write(f"{len(tets)} 4 0\n")
        for n, t in enumerate(tets):
            f.write(f"{n} {t[0]} {t[1]} {t[2]} {t[3]}\n")
    print(f"graded_slab: {len(points)} vertices, {len(tets)} tets")


if __name__ == "__main__":
    main()
