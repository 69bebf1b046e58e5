"""Regenerate the tetrahedral gmsh files of tests/meshes/3d (the meshes of tests/test_mesh3d.py).

Needs the gmsh Python package (``pip install gmsh``); the tests only read the files. Each file is a
real gmsh output of a small model: valid ones (a unit cube, a quarter ball, two cubes apart) and the
mistakes gmsh users make. A few mistakes gmsh itself never writes (two physical surfaces of one name,
a coordinate that is not a number, a flat, repeated or inverted tetrahedron) come from other programs and hand
edits: those files are gmsh's cube with one edit. Run from anywhere: ``python tests/meshes/make_meshes_3d.py``.
"""

import re
from pathlib import Path

import gmsh

HERE = Path(__file__).parent / "3d"
SIZE = 0.5
#: The faces of a box by the coordinate they fix: (axis, at the low end?) -> name.
FACES = {(0, True): "left", (0, False): "right", (1, True): "front", (1, False): "back", (2, True): "bottom",
         (2, False): "top"}


def write(name, build, *, version=4.1, order=1, size=SIZE):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    build()
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), size)
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(HERE / f"{name}.msh"))
    gmsh.finalize()


def box_faces(low=(0, 0, 0), high=(1, 1, 1)):
    """name -> surface tags of the faces of the box [low, high] (after synchronize)."""
    found = {}
    for _, tag in gmsh.model.getEntities(2):
        centre = gmsh.model.occ.getCenterOfMass(2, tag)
        for (axis, at_low), name in FACES.items():
            if abs(centre[axis] - (low[axis] if at_low else high[axis])) < 1e-9 and all(
                    low[a] - 1e-9 <= centre[a] <= high[a] + 1e-9 for a in range(3)):
                found.setdefault(name, []).append(tag)
    return found


def cube(volume=True, surfaces=True):
    """The unit cube; its faces are physical surfaces "left" ... "top" (tags 1 to 6) and "sides" (7:
    left, right, front, back, declared last, so in msh 4.1 those faces list "left"... first); the
    body is the physical volume "body" (8)."""
    def build():
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        faces = box_faces()
        if surfaces:
            for tag, name in enumerate(FACES.values(), start=1):
                gmsh.model.addPhysicalGroup(2, faces[name], tag=tag, name=name)
            gmsh.model.addPhysicalGroup(2, sum((faces[n] for n in ("left", "right", "front", "back")), []), tag=7,
                                        name="sides")
        if volume:
            gmsh.model.addPhysicalGroup(3, [1], tag=8, name="body")
    return build


def quarter_ball():
    """{x > 0, y > 0, x² + y² + (z − 1)² < 1} as two octants (above and below z = 1) sharing their
    face on z = 1: physical surfaces "sym_x", "sym_y", "top" (the upper sphere), "bottom", volume "body"."""
    occ = gmsh.model.occ
    octants = []
    for z in (0, 1):
        (octant,), _ = occ.intersect([(3, occ.addSphere(0, 0, 1, 1))], [(3, occ.addBox(0, 0, z, 1, 1, 1))])
        octants.append(octant)
    occ.fragment(octants[:1], octants[1:])
    occ.synchronize()
    groups = {"sym_x": [], "sym_y": [], "top": [], "bottom": []}
    for _, face in gmsh.model.getEntities(2):
        x, y, z = occ.getCenterOfMass(2, face)
        if abs(x) < 1e-9:
            groups["sym_x"].append(face)
        elif abs(y) < 1e-9:
            groups["sym_y"].append(face)
        elif abs(z - 1) > 1e-9:
            groups["top" if z > 1 else "bottom"].append(face)
    for name, faces in groups.items():
        gmsh.model.addPhysicalGroup(2, faces, name=name)
    gmsh.model.addPhysicalGroup(3, [tag for _, tag in gmsh.model.getEntities(3)], name="body")


def two_cubes(second, fragment=True):
    """The unit cube and the box [second, second + 1]: its faces and "body" = both; the boxes are
    fragmented (share what they touch) unless `fragment` is False."""
    def build():
        occ = gmsh.model.occ
        a = occ.addBox(0, 0, 0, 1, 1, 1)
        b = occ.addBox(*second, 1, 1, 1)
        if fragment:
            occ.fragment([(3, a)], [(3, b)])
        occ.synchronize()
        faces = box_faces()
        for name in ("left", "bottom"):
            gmsh.model.addPhysicalGroup(2, faces[name], name=name)
        gmsh.model.addPhysicalGroup(3, [tag for _, tag in gmsh.model.getEntities(3)], name="body")
    return build


def split_cube():
    """The unit cube as two halves x < 0.5 and x > 0.5 sharing their middle face, which is also a
    physical surface "middle" (inside the body: not a boundary)."""
    occ = gmsh.model.occ
    a = occ.addBox(0, 0, 0, 0.5, 1, 1)
    b = occ.addBox(0.5, 0, 0, 0.5, 1, 1)
    occ.fragment([(3, a)], [(3, b)])
    occ.synchronize()
    middle = [tag for _, tag in gmsh.model.getEntities(2)
              if abs(occ.getCenterOfMass(2, tag)[0] - 0.5) < 1e-9]
    gmsh.model.addPhysicalGroup(2, box_faces()["bottom"], name="bottom")
    gmsh.model.addPhysicalGroup(2, middle, name="middle")
    gmsh.model.addPhysicalGroup(3, [1, 2], name="body")


def regions():
    """The box [0, 2] × [0, 1] × [0, 1] as two unit cubes sharing x = 1 (fragmented): physical volumes
    "core" (x < 1), "shell" (x > 1) and "body" (both: every tetrahedron is in two physical volumes);
    physical surfaces "left" and "bottom"."""
    occ = gmsh.model.occ
    occ.fragment([(3, occ.addBox(0, 0, 0, 1, 1, 1))], [(3, occ.addBox(1, 0, 0, 1, 1, 1))])
    occ.synchronize()
    faces = box_faces(high=(2, 1, 1))
    for name in ("left", "bottom"):
        gmsh.model.addPhysicalGroup(2, faces[name], name=name)
    volumes = {round(occ.getCenterOfMass(3, tag)[0]): tag for _, tag in gmsh.model.getEntities(3)}
    gmsh.model.addPhysicalGroup(3, [volumes[0]], name="core")
    gmsh.model.addPhysicalGroup(3, [volumes[2]], name="shell")
    gmsh.model.addPhysicalGroup(3, [volumes[0], volumes[2]], name="body")


def hexahedra():
    """The unit cube meshed with transfinite hexahedra."""
    gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    for dim, tag in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(tag, 3)
    for dim, tag in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(tag)
        gmsh.model.mesh.setRecombine(2, tag)
    gmsh.model.mesh.setTransfiniteVolume(1)
    gmsh.model.addPhysicalGroup(2, box_faces()["bottom"], name="bottom")
    gmsh.model.addPhysicalGroup(3, [1], name="body")


def prisms():
    """A triangulated unit square extruded in two recombined layers: prisms (wedges)."""
    geo = gmsh.model.geo
    points = [geo.addPoint(x, y, 0, SIZE) for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)]]
    square = geo.addPlaneSurface([geo.addCurveLoop([geo.addLine(points[i], points[(i + 1) % 4]) for i in range(4)])])
    extruded = geo.extrude([(2, square)], 0, 0, 1, numElements=[2], recombine=True)
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, [square], name="bottom")
    gmsh.model.addPhysicalGroup(3, [tag for dim, tag in extruded if dim == 3], name="body")


def pyramids():
    """The unit cube of tetrahedra with its bottom face recombined into quadrilaterals: gmsh joins
    them to the tetrahedra with pyramids."""
    gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    bottom = box_faces()["bottom"]
    gmsh.model.mesh.setRecombine(2, bottom[0])
    gmsh.model.addPhysicalGroup(2, bottom, name="bottom")
    gmsh.model.addPhysicalGroup(3, [1], name="body")


def edit(source, target, change):
    """Write `target` as the text of `source` with `change(text)` applied (an edit gmsh never makes)."""
    text = (HERE / f"{source}.msh").read_text()
    changed = change(text)
    assert changed != text, target
    (HERE / f"{target}.msh").write_text(changed)


def element_lines(text):
    """The lines of the $Elements section of a msh 2.2 text, and where the section starts."""
    head, rest = text.split("$Elements\n", 1)
    count, rest = rest.split("\n", 1)
    body, tail = rest.split("$EndElements", 1)
    return head + "$Elements\n" + count + "\n", body.splitlines(), "$EndElements" + tail


def first_tetrahedron(lines, inner_node=None):
    """Index of the first tetrahedron line (type 4), optionally one with the node `inner_node`."""
    for i, line in enumerate(lines):
        fields = line.split()
        if fields[1] == "4" and (inner_node is None or inner_node in fields[-4:]):
            return i
    raise ValueError("no tetrahedron")


def repeat_node(text):
    """The first tetrahedron gets its first node twice (zero volume)."""
    head, lines, tail = element_lines(text)
    i = first_tetrahedron(lines)
    fields = lines[i].split()
    fields[-1] = fields[-4]
    lines[i] = " ".join(fields)
    return head + "\n".join(lines) + "\n" + tail


def inner_node(text):
    """The number of a node inside the unit cube (no coordinate 0 or 1)."""
    nodes = text.split("$Nodes\n", 1)[1].split("$EndNodes", 1)[0].splitlines()[1:]
    for line in nodes:
        number, *xyz = line.split()
        if all(0.0 < float(c) < 1.0 for c in xyz):
            return number
    raise ValueError("no inner node")


def tetrahedron_twice(text):
    """A tetrahedron at a node inside the cube written twice (as a new element at the end)."""
    head, lines, tail = element_lines(text)
    i = first_tetrahedron(lines, inner_node(text))
    fields = lines[i].split()
    fields[0] = str(len(lines) + 1)
    lines.append(" ".join(fields))
    head = re.sub(r"\$Elements\n\d+\n", f"$Elements\n{len(lines)}\n", head)
    return head + "\n".join(lines) + "\n" + tail


def pulled_node(text):
    """The first node inside the cube pulled out through its right face (x = 1.3): the tetrahedra around
    it turn inside out."""
    number = inner_node(text)
    return re.sub(rf"(?m)^{number} \S+ ", f"{number} 1.3 ", text, count=1)


def nan_coordinate(text):
    """The first node inside the cube gets the x coordinate nan."""
    number = inner_node(text)
    return re.sub(rf"(?m)^{number} \S+ ", f"{number} nan ", text, count=1)


if __name__ == "__main__":
    HERE.mkdir(exist_ok=True)
    write("cube", cube())
    write("cube_msh22", cube(), version=2.2)
    write("quarter_ball", quarter_ball, size=0.25)
    write("two_cubes_apart", two_cubes((2, 0, 0)))
    write("no_physical_volume", cube(volume=False))
    write("no_physical_groups", cube(volume=False, surfaces=False))
    write("second_order", cube(), order=2)
    write("regions", regions)
    write("regions_msh22", regions, version=2.2)
    write("hexahedra", hexahedra)
    write("prisms", prisms)
    write("pyramids", pyramids)
    write("internal_surface", split_cube)
    write("seam", two_cubes((1, 0, 0), fragment=False))
    write("edge_hinge", two_cubes((1, 1, 0)))
    write("vertex_hinge", two_cubes((1, 1, 1)))
    # gmsh itself does not write these; other programs and hand edits do
    edit("cube_msh22", "duplicate_names", lambda text: text.replace('2 2 "right"', '2 2 "left"'))
    edit("cube_msh22", "nan_coordinate", nan_coordinate)
    edit("cube_msh22", "zero_volume", repeat_node)
    edit("cube_msh22", "face_of_three", tetrahedron_twice)
    edit("cube_msh22", "folded", pulled_node)
