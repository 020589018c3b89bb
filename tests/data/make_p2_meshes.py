#!/usr/bin/env python3
"""Generates the second-order Gmsh test meshes of tests/gmsh.rs (MSH 4.1 ASCII):

* tests/data/box_p1.msh: the box (0, 2) × (0, 1) × (0, 1) meshed with 4-node tetrahedra, its
  faces in the physical surfaces "bottom" (x₃ = 0), "top" (x₃ = 1) and "sides" (the four others),
  the volume in the physical volume "body";
* tests/data/box_p2.msh: the same mesh raised to order 2 (10-node tetrahedra, 6-node triangles)
  by `gmsh.model.mesh.setOrder(2)` after box_p1.msh was saved: the same vertices and elements
  (Gmsh renumbers the nodes, the element tags stay), an edge node at the midpoint of every edge;
* tests/data/cylinder_p2.msh: a coarse second-order mesh of the cylinder x₁² + x₂² ≤ 0.5²,
  0 ≤ x₃ ≤ 1 (physical surface "base" at x₃ = 0, volume "body"): the edge nodes on the curved
  side lie on the cylinder, off their edges' midpoints (the reader straightens them, with a
  warning).

Regenerate (needs the `gmsh` Python package, e.g. `pip install gmsh`; the committed files were made
with gmsh 4.15.2, which reproduces them byte for byte):

    python3 tests/data/make_p2_meshes.py
"""

import os
import sys

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))


def box():
    gmsh.model.add("box")
    occ = gmsh.model.occ
    volume = occ.addBox(0.0, 0.0, 0.0, 2.0, 1.0, 1.0)
    occ.synchronize()
    bottom, top, sides = [], [], []
    for dim, tag in gmsh.model.getBoundary([(3, volume)], oriented=False):
        _, _, zmin, _, _, zmax = gmsh.model.getBoundingBox(dim, tag)
        if zmax < 1e-5:
            bottom.append(tag)
        elif zmin > 1 - 1e-5:
            top.append(tag)
        else:
            sides.append(tag)
    assert len(bottom) == 1 and len(top) == 1 and len(sides) == 4, (bottom, top, sides)
    gmsh.model.addPhysicalGroup(2, bottom, name="bottom")
    gmsh.model.addPhysicalGroup(2, top, name="top")
    gmsh.model.addPhysicalGroup(2, sides, name="sides")
    gmsh.model.addPhysicalGroup(3, [volume], name="body")
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.4)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.4)
    gmsh.model.mesh.generate(3)
    gmsh.write(os.path.join(HERE, "box_p1.msh"))
    gmsh.model.mesh.setOrder(2)
    gmsh.write(os.path.join(HERE, "box_p2.msh"))


def cylinder():
    gmsh.model.add("cylinder")
    occ = gmsh.model.occ
    volume = occ.addCylinder(0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.5)
    occ.synchronize()
    base = []
    for dim, tag in gmsh.model.getBoundary([(3, volume)], oriented=False):
        _, _, zmin, _, _, zmax = gmsh.model.getBoundingBox(dim, tag)
        if zmax < 1e-5:
            base.append(tag)
    assert len(base) == 1, base
    gmsh.model.addPhysicalGroup(2, base, name="base")
    gmsh.model.addPhysicalGroup(3, [volume], name="body")
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.5)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    gmsh.write(os.path.join(HERE, "cylinder_p2.msh"))


def main():
    gmsh.initialize(sys.argv[:1])
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    # only the elements of physical groups: the tetrahedra of "body" and the group triangles
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    box()
    cylinder()
    for name in ["box_p1.msh", "box_p2.msh", "cylinder_p2.msh"]:
        path = os.path.join(HERE, name)
        print(f"{name}: {os.path.getsize(path)} bytes")
    gmsh.finalize()


if __name__ == "__main__":
    main()
