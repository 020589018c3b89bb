#!/usr/bin/env python3
"""Generates the Lamé meshes of tests/lame.rs and examples/cylinder.toml (MSH 4.1 ASCII, 4-node
tetrahedra; the scenes take them as P2, which adds the edge nodes at the midpoints):

a quarter of the thick-walled cylinder 1 ≤ r ≤ 2, 0 ≤ θ ≤ π/2, 0 ≤ x₃ ≤ 0.2, with the physical
surfaces "bore" (r = 1), "outer" (r = 2), "x0" (x₁ = 0), "y0" (x₂ = 0), "ends" (x₃ = 0 and
x₃ = 0.2), the volume "body"; mesh sizes h = 0.4, 0.2, 0.1 into lame_h0.4.msh, lame_h0.2.msh,
lame_h0.1.msh.

Regenerate (needs `pip install gmsh`; made with gmsh 4.15.2):

    python3 tests/data/make_lame_meshes.py
"""

import math
import os
import sys

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))
A, B, T = 1.0, 2.0, 0.2


def quarter(h):
    gmsh.model.add(f"lame_{h}")
    occ = gmsh.model.occ
    outer = occ.addCylinder(0, 0, 0, 0, 0, T, B, angle=math.pi / 2)
    inner = occ.addCylinder(0, 0, 0, 0, 0, T, A, angle=math.pi / 2)
    (body,), _ = occ.cut([(3, outer)], [(3, inner)])
    occ.synchronize()
    groups = {"bore": [], "outer": [], "x0": [], "y0": [], "ends": []}
    for dim, tag in gmsh.model.getBoundary([body], oriented=False):
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(dim, tag)
        if z1 - z0 < 1e-5:
            groups["ends"].append(tag)
        elif x1 < 1e-5:
            groups["x0"].append(tag)
        elif y1 < 1e-5:
            groups["y0"].append(tag)
        elif x1 < A + 1e-3:
            groups["bore"].append(tag)
        else:
            groups["outer"].append(tag)
    assert all(len(v) == (2 if k == "ends" else 1) for k, v in groups.items()), groups
    for name, tags in groups.items():
        gmsh.model.addPhysicalGroup(2, tags, name=name)
    gmsh.model.addPhysicalGroup(3, [body[1]], name="body")
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.model.mesh.generate(3)
    gmsh.write(os.path.join(HERE, f"lame_h{h}.msh"))


def main():
    gmsh.initialize(sys.argv[:1])
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    for h in (0.4, 0.2, 0.1):
        quarter(h)
    gmsh.finalize()


if __name__ == "__main__":
    main()
