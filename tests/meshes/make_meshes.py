"""Regenerate the gmsh files of this folder (the meshes of tests/test_mesh_validation.py).

Needs the gmsh Python package (``pip install gmsh``); the tests only read the files. Each file is a
real gmsh output of a small unit-square model: a valid one, and the mistakes gmsh users make. Run
from anywhere: ``python tests/meshes/make_meshes.py``.
"""

from pathlib import Path

import gmsh

HERE = Path(__file__).parent
SIZE = 0.5


def rectangle(x0, y0, x1, y1, size=SIZE):
    """A plane surface on a new rectangle (own points and lines): (surface, [bottom, right, top, left])."""
    geo = gmsh.model.geo
    points = [geo.addPoint(x, y, 0, size) for x, y in [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]]
    lines = [geo.addLine(points[i], points[(i + 1) % 4]) for i in range(4)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    return surface, lines


def physical_sides(lines, prefix=""):
    """Physical curves "bottom", "right", "top", "left" of `lines` (a line tag or a list of them each)."""
    for tags, name in zip(lines, ["bottom", "right", "top", "left"]):
        gmsh.model.addPhysicalGroup(1, tags if isinstance(tags, list) else [tags], name=prefix + name)


def write(name, build, *, version=4.1, dim=2, order=1):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    build()
    gmsh.model.geo.synchronize()
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.model.mesh.generate(dim)
    gmsh.write(str(HERE / f"{name}.msh"))
    gmsh.finalize()


def square(curves=True, surface=True, recombine=False):
    def build():
        s, lines = rectangle(0, 0, 1, 1)
        gmsh.model.geo.synchronize()
        if curves:
            physical_sides(lines)
        if surface:
            gmsh.model.addPhysicalGroup(2, [s], name="body")
        if recombine:
            gmsh.model.geo.mesh.setRecombine(2, s)
    return build


def mixed():
    """Two squares sharing a side, the right one recombined into quadrilaterals."""
    geo = gmsh.model.geo
    points = [geo.addPoint(x, y, 0, SIZE) for x, y in [(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (0, 1)]]
    b1, b2, r, t2, t1, l, mid = (geo.addLine(points[a], points[b]) for a, b in
                                 [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0), (1, 4)])
    left = geo.addPlaneSurface([geo.addCurveLoop([b1, mid, t1, l])])
    right = geo.addPlaneSurface([geo.addCurveLoop([b2, r, t2, -mid])])
    geo.mesh.setRecombine(2, right)
    geo.synchronize()
    gmsh.model.addPhysicalGroup(1, [b1, b2], name="bottom")
    gmsh.model.addPhysicalGroup(1, [l], name="left")
    gmsh.model.addPhysicalGroup(2, [left, right], name="body")


def two_bodies():
    """Two squares apart: [0, 1]² with its sides, and [2, 3] × [0, 1] ("other_bottom" only)."""
    s1, lines1 = rectangle(0, 0, 1, 1)
    s2, lines2 = rectangle(2, 0, 3, 1)
    gmsh.model.geo.synchronize()
    physical_sides(lines1)
    gmsh.model.addPhysicalGroup(1, [lines2[0]], name="other_bottom")
    gmsh.model.addPhysicalGroup(2, [s1, s2], name="body")


def crack():
    """[0, 2] × [0, 1] as two squares built on their own points and lines: nothing joins them at x = 1
    (no Coherence), so the nodes on x = 1 are there twice."""
    s1, lines1 = rectangle(0, 0, 1, 1)
    s2, lines2 = rectangle(1, 0, 2, 1)
    gmsh.model.geo.synchronize()
    gmsh.model.addPhysicalGroup(1, [lines1[0], lines2[0]], name="bottom")
    gmsh.model.addPhysicalGroup(1, [lines1[3]], name="left")
    gmsh.model.addPhysicalGroup(1, [lines2[1]], name="right")
    gmsh.model.addPhysicalGroup(2, [s1, s2], name="body")


def overlapping_squares():
    """[0, 1]² and [0.5, 1.5] × [0.25, 1.25] meshed independently: they cover a region twice."""
    s1, lines1 = rectangle(0, 0, 1, 1)
    s2, _ = rectangle(0.5, 0.25, 1.5, 1.25)
    gmsh.model.geo.synchronize()
    physical_sides(lines1)
    gmsh.model.addPhysicalGroup(2, [s1, s2], name="body")


def surface_twice():
    """Two plane surfaces on the same curve loop: the square is meshed twice."""
    geo = gmsh.model.geo
    points = [geo.addPoint(x, y, 0, SIZE) for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)]]
    lines = [geo.addLine(points[i], points[(i + 1) % 4]) for i in range(4)]
    loop = geo.addCurveLoop(lines)
    first, second = geo.addPlaneSurface([loop]), geo.addPlaneSurface([loop])
    geo.synchronize()
    physical_sides(lines)
    gmsh.model.addPhysicalGroup(2, [first, second], name="body")


def shared_curves():
    """The square with a curve in two named groups: "contact" = bottom + right, "corner" = bottom
    (declared first, so in msh 4.1 the bottom curve lists "corner" first)."""
    s, (bottom, right, top, left) = rectangle(0, 0, 1, 1)
    gmsh.model.geo.synchronize()
    gmsh.model.addPhysicalGroup(1, [bottom], name="corner")
    gmsh.model.addPhysicalGroup(1, [bottom, right], name="contact")
    gmsh.model.addPhysicalGroup(1, [left], name="left")
    gmsh.model.addPhysicalGroup(2, [s], name="body")


def regions():
    """[0, 2] × [0, 1] as two squares sharing x = 1: physical surfaces "core" (x < 1), "shell" (x > 1)
    and "body" (both: every triangle is in two physical surfaces); sides "bottom" ... "left"."""
    geo = gmsh.model.geo
    points = [geo.addPoint(x, y, 0, SIZE) for x, y in [(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (0, 1)]]
    b1, b2, r, t2, t1, l, mid = (geo.addLine(points[a], points[b]) for a, b in
                                 [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0), (1, 4)])
    core = geo.addPlaneSurface([geo.addCurveLoop([b1, mid, t1, l])])
    shell = geo.addPlaneSurface([geo.addCurveLoop([b2, r, t2, -mid])])
    geo.synchronize()
    physical_sides([[b1, b2], [r], [t1, t2], [l]])
    gmsh.model.addPhysicalGroup(2, [core], name="core")
    gmsh.model.addPhysicalGroup(2, [shell], name="shell")
    gmsh.model.addPhysicalGroup(2, [core, shell], name="body")


def edit_elements(source, target, change):
    """Write `target` as the msh 2.2 file `source` with its element lines replaced by change(lines)."""
    head, rest = (HERE / f"{source}.msh").read_text().split("$Elements\n", 1)
    lines, tail = rest.split("$EndElements", 1)
    lines = change(lines.splitlines()[1:])
    (HERE / f"{target}.msh").write_text(f"{head}$Elements\n{len(lines)}\n" + "\n".join(lines) + "\n$EndElements"
                                        + tail)


def untagged_shell(lines):
    """Drop the triangles of "body" (7) and give those of "shell" (6) the physical tag 0 (none)."""
    kept = [line.split() for line in lines if line.split()[1:4:2] != ["2", "7"]]
    return [" ".join(f[:3] + (["0"] if f[1:4:2] == ["2", "6"] else f[3:4]) + f[4:]) for f in kept]


def triangle_twice(lines):
    """The first triangle of "core" (5) written once more in "core"."""
    first = next(line.split() for line in lines if line.split()[1:4:2] == ["2", "5"])
    return lines + [" ".join([str(len(lines) + 1)] + first[1:])]


def cube():
    gmsh.model.geo.synchronize()
    gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMin", 1.0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 1.0)
    gmsh.model.addPhysicalGroup(3, [1], name="body")
    gmsh.model.addPhysicalGroup(2, [1], name="bottom")


if __name__ == "__main__":
    write("square", square())
    write("square_msh22", square(), version=2.2)
    write("no_physical_surface", square(surface=False))
    write("no_physical_groups", square(curves=False, surface=False))
    write("second_order", square(), order=2)
    write("quadrilaterals", square(recombine=True))
    write("mixed_triangles_quads", mixed)
    write("two_bodies", two_bodies)
    write("crack", crack)
    write("overlapping_squares", overlapping_squares)
    write("surface_twice", surface_twice)
    write("shared_curves", shared_curves)
    write("shared_curves_msh22", shared_curves, version=2.2)
    write("cube", cube, dim=3)
    write("regions", regions)
    write("regions_msh22", regions, version=2.2)
    # gmsh itself does not write two physical curves of one name; other tools and hand edits do
    text = (HERE / "square_msh22.msh").read_text()
    (HERE / "duplicate_names.msh").write_text(text.replace('1 2 "right"', '1 2 "bottom"'))
    # triangles of no physical group beside tagged ones (gmsh's Mesh.SaveAll drops all tags in msh 2.2)
    edit_elements("regions_msh22", "regions_untagged_shell", untagged_shell)
    edit_elements("regions_msh22", "regions_triangle_twice", triangle_twice)
    (HERE / "regions_duplicate_names.msh").write_text(
        (HERE / "regions_msh22.msh").read_text().replace('2 6 "shell"', '2 6 "core"'))
