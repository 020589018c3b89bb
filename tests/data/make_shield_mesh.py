#!/usr/bin/env python3
"""Generates the Gmsh mesh of Shield's circular flat punch (examples/circular_punch_gmsh.toml,
theory §13): one quarter of the half-space by the box [0, 3]³, the punch the quarter disc
x₁² + x₂² ≤ 1 on x₃ = 0, fragmented into the bottom face so that its rim — where the stresses
are singular and the collapse mechanism turns — lies on element edges.

Physical surfaces (facet groups by name):

* "punch"  the quarter disc (the punch face),
* "free"   the rest of the bottom face x₃ = 0,
* "xmin", "ymin"  the symmetry planes,
* "far"    x₁ = 3, x₂ = 3, x₃ = 3 (standing in for the half-space at infinity),

and the volume "body". The mesh size is SIZE_RIM at the rim (the quarter circle) and grows
linearly with the distance from it to SIZE_NEAR at RIM_DISTANCE; within NEAR_DISTANCE of the
punch face it is at most SIZE_NEAR; far away SIZE_FAR.

    python3 tests/data/make_shield_mesh.py [--scale S] OUT.msh

`--scale S` multiplies every size (S < 1 refines). Made with gmsh 4.15.2.
"""

import math
import sys

import gmsh

SIZE_RIM = 0.04
SIZE_NEAR = 0.2
RIM_DISTANCE = 0.6
NEAR_DISTANCE = 1.0
SIZE_FAR = 0.6
RADIUS = 1.0
SIDE = 3.0


def build(scale):
    occ = gmsh.model.occ
    box = occ.addBox(0.0, 0.0, 0.0, SIDE, SIDE, SIDE)
    disc = occ.addDisk(0.0, 0.0, 0.0, RADIUS, RADIUS)
    occ.fragment([(3, box)], [(2, disc)])
    occ.synchronize()
    # the part of the disc outside the box (x₁ < 0 or x₂ < 0) is a free surface: remove it
    volumes = gmsh.model.getEntities(3)
    assert len(volumes) == 1, volumes
    boundary = {t for _, t in gmsh.model.getBoundary(volumes, oriented=False)}
    stray = [(d, t) for d, t in gmsh.model.getEntities(2) if t not in boundary]
    occ.remove(stray, recursive=True)
    occ.synchronize()

    groups = {"punch": [], "free": [], "xmin": [], "ymin": [], "far": []}
    for _, tag in gmsh.model.getBoundary(volumes, oriented=False):
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(2, tag)
        eps = 1e-5
        if abs(z0) < eps and abs(z1) < eps:
            groups["punch" if max(x1, y1) < RADIUS + eps else "free"].append(tag)
        elif abs(x0) < eps and abs(x1) < eps:
            groups["xmin"].append(tag)
        elif abs(y0) < eps and abs(y1) < eps:
            groups["ymin"].append(tag)
        else:
            groups["far"].append(tag)
    assert [len(groups[k]) for k in groups] == [1, 1, 1, 1, 3], groups
    for name, tags in groups.items():
        gmsh.model.addPhysicalGroup(2, tags, name=name)
    gmsh.model.addPhysicalGroup(3, [v[1] for v in volumes], name="body")

    # the rim: the curve of the punch face that is neither on x₁ = 0 nor on x₂ = 0
    rim = []
    for _, c in gmsh.model.getBoundary([(2, groups["punch"][0])], oriented=False):
        x0, y0, _, x1, y1, _ = gmsh.model.getBoundingBox(1, c)
        if x1 - x0 > 1e-3 and y1 - y0 > 1e-3:
            rim.append(c)
    assert len(rim) == 1, rim
    field = gmsh.model.mesh.field
    d_rim = field.add("Distance")
    field.setNumbers(d_rim, "CurvesList", rim)
    field.setNumber(d_rim, "Sampling", 200)
    t_rim = field.add("Threshold")
    field.setNumber(t_rim, "InField", d_rim)
    field.setNumber(t_rim, "SizeMin", SIZE_RIM * scale)
    field.setNumber(t_rim, "SizeMax", SIZE_FAR * scale)
    field.setNumber(t_rim, "DistMin", 0.0)
    field.setNumber(t_rim, "DistMax", RIM_DISTANCE * (SIZE_FAR / SIZE_NEAR))
    d_face = field.add("Distance")
    field.setNumbers(d_face, "SurfacesList", groups["punch"])
    field.setNumber(d_face, "Sampling", 40)
    t_face = field.add("Threshold")
    field.setNumber(t_face, "InField", d_face)
    field.setNumber(t_face, "SizeMin", SIZE_NEAR * scale)
    field.setNumber(t_face, "SizeMax", SIZE_FAR * scale)
    field.setNumber(t_face, "DistMin", NEAR_DISTANCE)
    field.setNumber(t_face, "DistMax", 2.0 * NEAR_DISTANCE)
    smallest = field.add("Min")
    field.setNumbers(smallest, "FieldsList", [t_rim, t_face])
    field.setAsBackgroundMesh(smallest)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.mesh.generate(3)


def report():
    types, tags, _ = gmsh.model.mesh.getElements(3)
    n_tets = sum(len(t) for ty, t in zip(types, tags) if ty == 4)
    n_nodes = len(gmsh.model.mesh.getNodes()[0])
    area = 0.0
    punch = [t for d, t in gmsh.model.getPhysicalGroups(2) if gmsh.model.getPhysicalName(d, t) == "punch"][0]
    node_tags, xyz, _ = gmsh.model.mesh.getNodes()
    coords = {t: xyz[3 * i : 3 * i + 3] for i, t in enumerate(node_tags)}
    for ent in gmsh.model.getEntitiesForPhysicalGroup(2, punch):
        _, _, nodes = gmsh.model.mesh.getElements(2, ent)
        tri = nodes[0]
        for k in range(0, len(tri), 3):
            a, b, c = (coords[tri[k + j]] for j in range(3))
            area += 0.5 * abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    print(f"{n_nodes} nodes, {n_tets} tetrahedra; punch face area {area:.6f} = {area / (math.pi / 4):.6f} π/4")


def main():
    args = sys.argv[1:]
    scale = 1.0
    if args[:1] == ["--scale"]:
        scale = float(args[1])
        args = args[2:]
    gmsh.initialize(sys.argv[:1])
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("shield")
    build(scale)
    report()
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(args[0])
    gmsh.finalize()


if __name__ == "__main__":
    main()
