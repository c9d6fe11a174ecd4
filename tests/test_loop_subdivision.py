"""Loop subdivision as pbrt-v4's `loopsubdiv` makes it (app/scene/loop_subdivision.py): one level's
new vertices against the rules written out by hand, the limit positions against the surface that
many more levels converge to, the limit normals against that surface's, and the pbrt-v4 reader's
shape. Each case fails with a rule changed (Loop's original beta for Warren's, the boundary's 1/8
for 1/5, the limit's gamma, the ring's order)."""

import numpy as np
import pytest

from pathtrace.errors import UserError
from pathtrace.scene.loop_subdivision import _Rings, control_topology, loop_subdivide, refine
from pathtrace.scene.meshes import vertex_normals

# a closed octahedron (every vertex of 4 neighbours), wound counter-clockwise seen from outside
OCTAHEDRON = (np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float),
              np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]))
# a disk of six triangles about a raised centre, its rim wavy: the rim is its boundary
_ANGLES = np.linspace(0, 2 * np.pi, 7)[:-1]
FAN = (np.vstack([[0, 0, 0.4], np.column_stack([np.cos(_ANGLES), np.sin(_ANGLES), 0.1 * np.cos(3 * _ANGLES)])]),
       np.array([[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)]))


def refined(mesh, levels, topology=False):
    """The mesh after `levels` levels (and its topology), not pushed to the limit."""
    p, f = mesh
    t = control_topology(np.asarray(f), len(p))
    for _ in range(levels):
        p, t = refine(p, t, _Rings(t))
    return (p, t.faces, t) if topology else (p, t.faces)


def test_one_level_moves_and_adds_vertices_by_warrens_weights():
    """An old interior vertex of n neighbours goes to (1 - n beta) p + beta (their sum), beta =
    3 / (8 n) (3/16 for n = 3); an interior edge's new vertex is 3/8 of its ends and 1/8 of the
    two corners facing it; each triangle becomes four, wound as it was."""
    v, f = OCTAHEDRON
    p, faces = refined(OCTAHEDRON, 1)
    assert len(faces) == 4 * len(f) and len(p) == 6 + 12
    beta = 3 / 32
    np.testing.assert_allclose(p[0], (1 - 4 * beta) * v[0] + beta * (v[2] + v[3] + v[4] + v[5]))
    np.testing.assert_allclose(p[4], (1 - 4 * beta) * v[4] + beta * (v[0] + v[1] + v[2] + v[3]))
    odd = p[6:]
    edge_02 = 3 / 8 * (v[0] + v[2]) + 1 / 8 * (v[4] + v[5])
    assert np.min(np.linalg.norm(odd - edge_02, axis=1)) < 1e-12
    # the children face the parent's way (outwards here)
    n_child = np.cross(p[faces[:, 1]] - p[faces[:, 0]], p[faces[:, 2]] - p[faces[:, 0]])
    centre = p[faces].mean(axis=1)
    assert np.all(np.sum(n_child * centre, axis=1) > 0)


def test_the_boundary_moves_along_itself():
    """A boundary vertex goes to 3/4 p + 1/8 of its two boundary neighbours, whatever its others
    (the centre here); a boundary edge's new vertex is its midpoint, an interior edge's 3/8 of its
    ends and 1/8 of the corners facing it; the centre (interior, 6 neighbours) takes beta = 1/16."""
    v, f = FAN
    p, _ = refined(FAN, 1)
    np.testing.assert_allclose(p[3], 0.75 * v[3] + 0.125 * (v[2] + v[4]))
    np.testing.assert_allclose(p[1], 0.75 * v[1] + 0.125 * (v[6] + v[2]))
    np.testing.assert_allclose(p[0], (1 - 6 / 16) * v[0] + v[1:].sum(axis=0) / 16, atol=1e-12)
    for new in (0.5 * (v[2] + v[3]), 3 / 8 * (v[0] + v[2]) + 1 / 8 * (v[1] + v[3])):
        assert np.min(np.linalg.norm(p[7:] - new, axis=1)) < 1e-12


@pytest.mark.parametrize("mesh", [OCTAHEDRON, FAN], ids=["closed", "open"])
def test_limit_positions_are_where_more_levels_converge(mesh):
    """Two levels pushed to the limit: an interior vertex where five more levels take it (its
    limit mask, gamma = 1 / (n + 3 / (8 beta))); a boundary vertex at pbrt-v4's 3/5 p + 1/5 of its
    boundary neighbours (pbrt-v4's rule, which the cubic B-spline's 2/3 and 1/6 would not give)."""
    limit, faces, _ = loop_subdivide(*mesh, levels=2)
    p2, f2, t = refined(mesh, 2, topology=True)
    fine, _ = refined((p2, f2), 5)         # 3e-5 off the limit, a quarter of that a level on
    _, boundary_sum = _Rings(t).sums(p2)
    inner, edge = ~t.boundary, t.boundary
    np.testing.assert_allclose(limit[inner], fine[:len(p2)][inner], atol=1e-4)
    np.testing.assert_allclose(limit[edge], 0.6 * p2[edge] + 0.2 * boundary_sum[edge], atol=1e-12)
    assert np.array_equal(faces, f2)


@pytest.mark.parametrize("mesh", [OCTAHEDRON, FAN], ids=["closed", "open"])
def test_limit_normals_are_the_limit_surfaces_and_point_as_pbrts(mesh):
    """The normal of each vertex (S x T of its limit tangents) lies along the normal of the surface
    five more levels make there; pbrt-v4 walks a vertex's ring against its triangles' winding
    (SDVertex::oneRing), so the normal points away from the side counter-clockwise triangles
    face, and pbrt-v4 turns the surface to it (its geometric normals follow the shading ones)."""
    limit, faces, normals = loop_subdivide(*mesh, levels=2)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-12)
    fine, fine_faces = refined(refined(mesh, 2), 5)
    along = np.sum(normals * vertex_normals(fine, fine_faces)[:len(limit)], axis=1)
    assert np.all(along < -0.999), along.max()


def test_every_control_triangle_is_subdivided_and_bad_input_refused():
    """A control triangle of zero area is subdivided as the rest (pbrt-v4 keeps it, and its
    children have area: dropping it moved a neighbour's limit point by 0.08); a triangle that
    repeats a vertex and a negative level count are refused."""
    # a square fan, and a triangle of no area on its right edge (vertex 5 lies between 1 and 2)
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0], [1, 0.5, 0]], float)
    f = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [1, 5, 2]])
    limit, faces, normals = loop_subdivide(v, f, 2)
    assert len(faces) == 16 * len(f) and np.all(np.isfinite(limit)) and np.all(np.isfinite(normals))
    with pytest.raises(ValueError, match="repeats a vertex"):
        loop_subdivide(v, np.array([[0, 0, 1]]), 1)
    with pytest.raises(ValueError, match="negative"):
        loop_subdivide(v, f, -1)


def test_the_reader_subdivides_levels_times(tmp_path):
    """pbrt-v4's `loopsubdiv`: 4^levels triangles of each (levels 3 by default), the limit's
    vertices and normals, faces wound to the normals as every pbrt mesh's are; a mesh its walk
    cannot follow, or one whose subdivision would be too large, is one line naming the shape."""
    from pathtrace.scene import load_scene
    v, f = OCTAHEDRON
    shape = f'Shape "loopsubdiv" "point3 P" [ {" ".join(map(str, v.ravel()))} ] ' \
            f'"integer indices" [ {" ".join(map(str, f.ravel()))} ]'
    for levels, expected in ((None, 8 * 64), (1, 8 * 4), (0, 8)):
        path = tmp_path / f"s{levels}.pbrt"
        path.write_text("WorldBegin\n" + (shape if levels is None else shape + f' "integer levels" {levels}') + "\n")
        mesh, = load_scene(str(path)).meshes
        assert len(mesh.faces) == expected and mesh.normals is not None
        wound = np.cross(mesh.vertices[mesh.faces[:, 1]] - mesh.vertices[mesh.faces[:, 0]],
                         mesh.vertices[mesh.faces[:, 2]] - mesh.vertices[mesh.faces[:, 0]])
        assert np.all(np.sum(wound * mesh.normals[mesh.faces].sum(axis=1), axis=1) > 0)
    path = tmp_path / "bad.pbrt"
    path.write_text('WorldBegin\nShape "loopsubdiv" "point3 P" [ 0 0 0 1 0 0 0 1 0 0 0 1 1 1 1 ] '
                    '"integer indices" [ 0 1 2  0 1 3 ]\n')
    with pytest.raises(UserError, match="bad.pbrt:2: .*run it the same way") as e:
        load_scene(str(path))
    assert "\n" not in str(e.value)
    path.write_text("WorldBegin\n" + shape + ' "integer levels" 12\n')
    with pytest.raises(UserError, match="bad.pbrt:2: 'levels': 12 levels make 134,217,728 triangles of 8, more than"):
        load_scene(str(path))


def test_a_sheet_listed_twice_wound_both_ways_is_a_pillow_as_pbrt_joins_it():
    """pbrt-v4 joins a control mesh's triangles across an edge two by two in the order it names
    them, and each level's children as their parents were: a triangle listed twice, wound both
    ways, is a closed pillow of two sides (its limit surface a lens, both sides' normals away from
    each other), and a square sheet listed so a flat pillow too. Joined by their corners' numbers
    instead, the children's edges between new vertices had four triangles, and the second level
    was refused."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    limit, faces, normals = loop_subdivide(v, np.array([[0, 1, 2], [0, 2, 1]]), 3)
    assert len(faces) == 2 * 64 and np.all(np.isfinite(limit)) and np.all(np.isfinite(normals))
    # every vertex lies in the triangle's plane (z = 0) and its normal is +z or -z
    np.testing.assert_allclose(limit[:, 2], 0, atol=1e-12)
    np.testing.assert_allclose(np.abs(normals[:, 2]), 1, atol=1e-9)
    # the two sides' triangles face away from each other
    corners = limit[faces]
    wound = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2]
    assert np.sum(wound > 0) == np.sum(wound < 0) == 64
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    top = [[0, 1, 2], [0, 2, 3]]
    limit, faces, normals = loop_subdivide(square, np.array(top + [c[::-1] for c in top]), 2)
    assert len(faces) == 4 * 16 and np.all(np.isfinite(normals))
    np.testing.assert_allclose(limit[:, 2], 0, atol=1e-12)


class _Vertex:
    def __init__(self, p):
        self.p, self.start, self.child, self.boundary = np.asarray(p, float), None, None, False


class _Face:
    def __init__(self):
        self.v, self.f, self.children = [None] * 3, [None] * 3, [None] * 4

    def at(self, v):
        return next(k for k in range(3) if self.v[k] is v)

    def next_face(self, v):
        return self.f[self.at(v)]

    def prev_face(self, v):
        return self.f[(self.at(v) + 2) % 3]


def _ring(v):
    """pbrt-v4's SDVertex::oneRing, as its user's guide and book describe the walk."""
    face, out = v.start, []
    if not v.boundary:
        while True:
            out.append(face.v[(face.at(v) + 1) % 3].p)
            face = face.next_face(v)
            if face is v.start:
                return out
    while face.next_face(v) is not None:
        face = face.next_face(v)
    out.append(face.v[(face.at(v) + 1) % 3].p)
    while face is not None:
        out.append(face.v[(face.at(v) + 2) % 3].p)
        face = face.prev_face(v)
    return out


def _beta(n):
    return 3 / 16 if n == 3 else 3 / (8 * n)


def _limit_normal(v):
    """S x T of the limit surface's tangents at v, from its ring (pbrt-v4's rules, as the book's
    Loop subdivision section gives them), unit length."""
    ring = _ring(v)
    n = len(ring)
    if v.boundary:
        s = ring[-1] - ring[0]
        if n == 2:
            t = ring[0] + ring[1] - 2 * v.p
        elif n == 3:
            t = ring[1] - v.p
        elif n == 4:
            t = -ring[0] + 2 * ring[1] + 2 * ring[2] - ring[3] - 2 * v.p
        else:
            theta = np.pi / (n - 1)
            t = -(np.sin(theta) * (ring[0] + ring[-1])
                  + sum((2 * np.cos(theta) - 2) * np.sin(k * theta) * ring[k] for k in range(1, n - 1)))
    else:
        s = sum(np.cos(2 * np.pi * k / n) * ring[k] for k in range(n))
        t = sum(np.sin(2 * np.pi * k / n) * ring[k] for k in range(n))
    c = np.cross(s, t)
    return c / np.linalg.norm(c)


def walked_loop_subdivision(points, triangles, levels):
    """An object-by-object Loop subdivision with pbrt-v4's topology (its faces joined across an
    edge two by two in their order, each level's children as their parents, a new vertex per pair
    of corners from the first face that has it, each ring walked from its start face): the
    reference for loop_subdivide's arrays. Returns each face's corners' limit points and normals."""
    verts, faces = [_Vertex(p) for p in points], [_Face() for _ in triangles]
    for face, tri in zip(faces, triangles):
        face.v = [verts[i] for i in tri]
        for v in face.v:
            v.start = face
    open_edges = {}
    for face in faces:
        for k in range(3):
            key = frozenset((id(face.v[k]), id(face.v[(k + 1) % 3])))
            if key in open_edges:
                other, j = open_edges.pop(key)
                other.f[j], face.f[k] = face, other
            else:
                open_edges[key] = (face, k)
    for v in verts:
        face = v.start
        while True:
            face = face.next_face(v)
            if face is None or face is v.start:
                break
        v.boundary = face is None
    for _ in range(levels):
        new_faces, new_verts = [], []
        for v in verts:
            v.child = _Vertex(0)
            v.child.boundary = v.boundary
            ring = _ring(v)
            b = _beta(len(ring))
            v.child.p = 0.75 * v.p + 0.125 * (ring[0] + ring[-1]) if v.boundary else \
                (1 - len(ring) * b) * v.p + b * sum(ring)
            new_verts.append(v.child)
        for face in faces:
            face.children = [_Face() for _ in range(4)]
            new_faces += face.children
        odd = {}
        for face in faces:
            for k in range(3):
                a, c = face.v[k], face.v[(k + 1) % 3]
                key = frozenset((id(a), id(c)))
                if key not in odd:
                    o = _Vertex(0)
                    o.boundary, o.start = face.f[k] is None, face.children[3]
                    if o.boundary:
                        o.p = 0.5 * (a.p + c.p)
                    else:
                        facing = [w for w in face.v if w is not a and w is not c][0].p + \
                            [w for w in face.f[k].v if w is not a and w is not c][0].p
                        o.p = 0.375 * (a.p + c.p) + 0.125 * facing
                    odd[key] = o
                    new_verts.append(o)
        for v in verts:
            v.child.start = v.start.children[v.start.at(v)]
        for face in faces:
            for j in range(3):
                face.children[3].f[j] = face.children[(j + 1) % 3]
                face.children[j].f[(j + 1) % 3] = face.children[3]
                g = face.f[j]
                face.children[j].f[j] = None if g is None else g.children[g.at(face.v[j])]
                g = face.f[(j + 2) % 3]
                face.children[j].f[(j + 2) % 3] = None if g is None else g.children[g.at(face.v[j])]
        for face in faces:
            for j in range(3):
                face.children[j].v[j] = face.v[j].child
                o = odd[frozenset((id(face.v[j]), id(face.v[(j + 1) % 3])))]
                face.children[j].v[(j + 1) % 3] = face.children[(j + 1) % 3].v[j] = face.children[3].v[j] = o
        verts, faces = new_verts, new_faces
    limit = {}
    for v in verts:
        ring = _ring(v)
        n = len(ring)
        g = 1 / (n + 3 / (8 * _beta(n)))
        limit[id(v)] = 0.6 * v.p + 0.2 * (ring[0] + ring[-1]) if v.boundary else (1 - n * g) * v.p + g * sum(ring)
    for v in verts:               # every point moved, then the tangents from the moved rings
        v.p = limit[id(v)]
    normal = {id(v): _limit_normal(v) for v in verts}
    return (np.array([[limit[id(v)] for v in face.v] for face in faces]),
            np.array([[normal[id(v)] for v in face.v] for face in faces]))


# two cones at one apex (vertex 0), each closed by its base: two closed fans meet there
_CONES = (np.vstack([np.zeros((1, 3)), [[np.cos(a), np.sin(a), h] for h in (1, -1) for a in np.arange(3) * 2 * np.pi / 3]]),
          np.array([[0, 1 + k, 1 + (k + 1) % 3] for k in range(3)] + [[1, 3, 2]]
                   + [[0, 4 + (k + 1) % 3, 4 + k] for k in range(3)] + [[4, 5, 6]]))
# the first cone and, at its apex, a triangle of its own (a closed fan and an open one)
_PINCH = (np.vstack([_CONES[0][:4], [[1.5, 0.2, 0.3], [1.4, -0.4, -0.2]]]),
          np.vstack([_CONES[1][:4], [[0, 4, 5]]]))
_FIVE = np.array([[0, 0, 0], [1, 0, 0.1], [0, 1, 0], [0.2, 0.3, 1], [-1, -0.5, 0.4]], float)


@pytest.mark.parametrize("name", ["octahedron", "fan", "pillow", "sheet twice", "cones", "pinch, open last",
                                  "pinch, closed last", "bow tie", "third face on an edge"])
def test_the_arrays_subdivide_as_a_walk_over_pbrts_objects_does(name):
    """loop_subdivide's points and normals, face by face, against walked_loop_subdivision, which
    follows pbrt-v4's objects one by one (faces, their neighbours and children, rings walked from
    each vertex's start face). Where a vertex's faces are several fans (two cones at one apex, a
    closed fan and an open one, two triangles at one corner, a third face on an edge, which
    pbrt-v4 joins to none) the ring is the fan its start face is in, the last face naming it, and
    whether it is on the boundary is that fan's, as pbrt-v4 walks them."""
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0]], float)
    top = [[0, 1, 2], [0, 2, 3]]
    points, triangles = {"octahedron": OCTAHEDRON, "fan": FAN,
                         "pillow": (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.3]], float), np.array([[0, 1, 2], [0, 2, 1]])),
                         "sheet twice": (square, np.array(top + [c[::-1] for c in top])),
                         "cones": _CONES, "pinch, open last": _PINCH,
                         "pinch, closed last": (_PINCH[0], _PINCH[1][::-1]),
                         "bow tie": (_FIVE, np.array([[0, 1, 2], [0, 3, 4]])),
                         "third face on an edge": (_FIVE, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]))}[name]
    limit, faces, normals = loop_subdivide(points, triangles, 2)
    corners, corner_normals = walked_loop_subdivision(points, triangles, 2)
    np.testing.assert_allclose(limit[faces], corners, atol=1e-12)
    np.testing.assert_allclose(normals[faces], corner_normals, atol=1e-9)
