#!/usr/bin/env python3
"""Generates the Gmsh test meshes of the default scene (SPEC §6): tests/data/punch.msh (MSH 4.1
ASCII) and tests/data/punch_binary.msh (MSH 4.1 binary), the same mesh in both encodings.

Geometry (OpenCASCADE kernel): the block Ω = (−1, 1)² × (0, 1). Its bottom face x₃ = 0 is split by
boolean fragments into

* the contact disc x₁² + x₂² ≤ 0.5²                      → physical surface "contact" (Γ₀),
* the rest of the open square |x₁|, |x₂| < 0.75          → physical surface "free" (Γ₁ \\ Γ₀),
* the bottom frame outside the square, the four sides and
  the top                                                → physical surface "clamped" (Γ₂),

and the block is the physical volume "body". The mesh size is about 0.06 on the contact disc and
grows with the distance from it to about 0.3 far away, so the file stays small (a few thousand
tetrahedra) while the contact zone is resolved (SPEC §6 asks for at least 8 elements across it).

Regenerate (needs the `gmsh` Python package, e.g. `pip install gmsh`; the committed files were made
with gmsh 4.15.2, which reproduces them byte for byte):

    python3 tests/data/make_punch_mesh.py

Meshes made by another Gmsh version differ in their node and element counts; the tests in
tests/gmsh.rs check properties (groups, facet positions, the solution within a tolerance), not
counts, except where they compare the two encodings with each other.
"""

import math
import os
import sys

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))

# Mesh sizes: on the contact disc, and far from it.
SIZE_CONTACT = 0.06
SIZE_FAR = 0.3
# The size grows linearly from SIZE_CONTACT at the disc to SIZE_FAR at this distance from it.
GROWTH_DISTANCE = 0.7

CONTACT_RADIUS = 0.5
FREE_HALF_WIDTH = 0.75


def build():
    occ = gmsh.model.occ
    box = occ.addBox(-1.0, -1.0, 0.0, 2.0, 2.0, 1.0)
    disc = occ.addDisk(0.0, 0.0, 0.0, CONTACT_RADIUS, CONTACT_RADIUS)
    square = occ.addRectangle(-FREE_HALF_WIDTH, -FREE_HALF_WIDTH, 0.0, 2 * FREE_HALF_WIDTH, 2 * FREE_HALF_WIDTH)
    # Fragments make the disc and the square part of the block's bottom face: one conforming
    # volume whose boundary holds the disc, the square minus the disc, and the frame.
    occ.fragment([(3, box)], [(2, disc), (2, square)])
    occ.synchronize()

    volumes = gmsh.model.getEntities(3)
    assert len(volumes) == 1, f"expected one volume after the fragments, got {volumes}"
    contact, free, clamped = [], [], []
    for dim, tag in gmsh.model.getBoundary(volumes, oriented=False):
        xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(dim, tag)
        # (OpenCASCADE's bounding boxes are enlarged by its tolerance, ~1e-7)
        on_bottom = abs(zmin) < 1e-5 and abs(zmax) < 1e-5
        extent = max(abs(xmin), abs(ymin), abs(xmax), abs(ymax))
        if on_bottom and extent < CONTACT_RADIUS + 1e-5:
            contact.append(tag)
        elif on_bottom and extent < FREE_HALF_WIDTH + 1e-5:
            free.append(tag)
        else:
            clamped.append(tag)
    assert len(contact) == 1 and len(free) == 1, (contact, free, clamped)
    assert len(clamped) == 6, f"expected the frame, four sides and the top, got {clamped}"

    gmsh.model.addPhysicalGroup(2, contact, name="contact")
    gmsh.model.addPhysicalGroup(2, free, name="free")
    gmsh.model.addPhysicalGroup(2, clamped, name="clamped")
    gmsh.model.addPhysicalGroup(3, [v[1] for v in volumes], name="body")

    # Size field: SIZE_CONTACT on the disc, growing with the distance from it.
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "SurfacesList", contact)
    field.setNumber(distance, "Sampling", 40)
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    field.setNumber(threshold, "SizeMin", SIZE_CONTACT)
    field.setNumber(threshold, "SizeMax", SIZE_FAR)
    field.setNumber(threshold, "DistMin", 0.0)
    field.setNumber(threshold, "DistMax", GROWTH_DISTANCE)
    field.setAsBackgroundMesh(threshold)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", SIZE_FAR)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.mesh.generate(3)


def report():
    types, tags, _ = gmsh.model.mesh.getElements(3)
    n_tets = sum(len(t) for ty, t in zip(types, tags) if ty == 4)
    n_nodes = len(gmsh.model.mesh.getNodes()[0])
    print(f"{n_nodes} nodes, {n_tets} tetrahedra")
    for dim, ptag in gmsh.model.getPhysicalGroups(2):
        name = gmsh.model.getPhysicalName(dim, ptag)
        n = 0
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            types, tags, _ = gmsh.model.mesh.getElements(dim, ent)
            n += sum(len(t) for ty, t in zip(types, tags) if ty == 2)
        print(f"  physical surface {name!r} (tag {ptag}): {n} triangles")
    # element size on the disc: the longest edge of the triangles there
    contact_tag = [t for d, t in gmsh.model.getPhysicalGroups(2) if gmsh.model.getPhysicalName(d, t) == "contact"][0]
    ent = gmsh.model.getEntitiesForPhysicalGroup(2, contact_tag)[0]
    _, _, nodes = gmsh.model.mesh.getElements(2, ent)
    coords = {}
    node_tags, xyz, _ = gmsh.model.mesh.getNodes()
    for i, t in enumerate(node_tags):
        coords[t] = xyz[3 * i : 3 * i + 3]
    longest = 0.0
    tri = nodes[0]
    for k in range(0, len(tri), 3):
        p = [coords[tri[k + j]] for j in range(3)]
        for a in range(3):
            b = (a + 1) % 3
            longest = max(longest, math.dist(p[a], p[b]))
    print(f"  longest triangle edge on the contact disc: {longest:.4f}")


def main():
    # optional: `--scale S OUT.msh` writes one ASCII file with every mesh size multiplied by S
    # (benchmark meshes of the same family: S = 0.44 gives about 20k dofs), instead of the two
    # committed test files
    args = sys.argv[1:]
    outputs = [(os.path.join(HERE, "punch.msh"), 0), (os.path.join(HERE, "punch_binary.msh"), 1)]
    if args[:1] == ["--scale"]:
        global SIZE_CONTACT, SIZE_FAR
        SIZE_CONTACT *= float(args[1])
        SIZE_FAR *= float(args[1])
        outputs = [(args[2], 0)]
    gmsh.initialize(sys.argv[:1])
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("punch")
    build()
    report()
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    # Only the elements of physical groups are saved (the default when groups exist): the
    # tetrahedra of "body" and the triangles of the three surfaces.
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    for path, binary in outputs:
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.write(path)
    gmsh.finalize()


if __name__ == "__main__":
    main()
