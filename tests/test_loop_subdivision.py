"""Loop subdivision as pbrt-v4's `loopsubdiv` makes it (app/scene/loop_subdivision.py): one level's
new vertices against the rules written out by hand, the limit positions against the surface that
many more levels converge to, the limit normals against that surface's, and the pbrt-v4 reader's
shape. Each case fails with a rule changed (Loop's original beta for Warren's, the boundary's 1/8
for 1/5, the limit's gamma, the ring's order)."""

import numpy as np
import pytest

from pathtrace.errors import UserError
from pathtrace.scene.loop_subdivision import _Edges, _refine, loop_subdivide
from pathtrace.scene.meshes import vertex_normals

# a closed octahedron (every vertex of 4 neighbours), wound counter-clockwise seen from outside
OCTAHEDRON = (np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float),
              np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]))
# a disk of six triangles about a raised centre, its rim wavy: the rim is its boundary
_ANGLES = np.linspace(0, 2 * np.pi, 7)[:-1]
FAN = (np.vstack([[0, 0, 0.4], np.column_stack([np.cos(_ANGLES), np.sin(_ANGLES), 0.1 * np.cos(3 * _ANGLES)])]),
       np.array([[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)]))


def refined(mesh, levels):
    p, f = mesh
    for _ in range(levels):
        p, f = _refine(p, f, _Edges(p, f))
    return p, f


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
    np.testing.assert_allclose(p[0], (1 - 6 / 16) * v[0] + v[1:].sum(axis=0) / 16)
    for new in (0.5 * (v[2] + v[3]), 3 / 8 * (v[0] + v[2]) + 1 / 8 * (v[1] + v[3])):
        assert np.min(np.linalg.norm(p[7:] - new, axis=1)) < 1e-12


@pytest.mark.parametrize("mesh", [OCTAHEDRON, FAN], ids=["closed", "open"])
def test_limit_positions_are_where_more_levels_converge(mesh):
    """Two levels pushed to the limit: an interior vertex where five more levels take it (its
    limit mask, gamma = 1 / (n + 3 / (8 beta))); a boundary vertex at pbrt-v4's 3/5 p + 1/5 of its
    boundary neighbours (pbrt-v4's rule, which the cubic B-spline's 2/3 and 1/6 would not give)."""
    limit, faces, _ = loop_subdivide(*mesh, levels=2)
    p2, f2 = refined(mesh, 2)
    fine, _ = refined((p2, f2), 5)         # 3e-5 off the limit, a quarter of that a level on
    e = _Edges(p2, f2)
    inner = ~e.boundary
    np.testing.assert_allclose(limit[inner], fine[:len(p2)][inner], atol=1e-4)
    np.testing.assert_allclose(limit[e.boundary], 0.6 * p2[e.boundary] + 0.2 * e.boundary_sum[e.boundary], atol=1e-12)
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


def test_every_control_triangle_is_subdivided_and_a_pinched_vertex_refused():
    """A control triangle of zero area is subdivided as the rest (pbrt-v4 keeps it, and its
    children have area: dropping it moved a neighbour's limit point by 0.08); a vertex where two
    closed fans meet (two cones at one apex), which pbrt-v4 would walk half of, is refused, as are
    a triangle that repeats a vertex and a negative level count."""
    # a square fan, and a triangle of no area on its right edge (vertex 5 lies between 1 and 2)
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0], [1, 0.5, 0]], float)
    f = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [1, 5, 2]])
    limit, faces, normals = loop_subdivide(v, f, 2)
    assert len(faces) == 16 * len(f) and np.all(np.isfinite(limit)) and np.all(np.isfinite(normals))
    apex = np.zeros((1, 3))
    ring = np.array([[np.cos(a), np.sin(a), h] for h in (1, -1) for a in np.arange(3) * 2 * np.pi / 3])
    cones = np.vstack([apex, ring])
    faces = [[0, 1 + k, 1 + (k + 1) % 3] for k in range(3)] + [[1, 3, 2]] \
        + [[0, 4 + (k + 1) % 3, 4 + k] for k in range(3)] + [[4, 5, 6]]
    with pytest.raises(ValueError, match="a bow tie"):
        loop_subdivide(cones, np.array(faces), 1)
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
    for indices, problem in (("0 1 2  0 1 3  0 1 4", "shared by more than two triangles"),
                             ("0 1 2  0 1 3", "run it the same way"), ("0 1 2  0 3 4", "a bow tie")):
        path = tmp_path / "bad.pbrt"
        path.write_text('WorldBegin\nShape "loopsubdiv" "point3 P" [ 0 0 0 1 0 0 0 1 0 0 0 1 1 1 1 ] '
                        f'"integer indices" [ {indices} ]\n')
        with pytest.raises(UserError, match=f"bad.pbrt:2: .*{problem}") as e:
            load_scene(str(path))
        assert "\n" not in str(e.value)
    path.write_text("WorldBegin\n" + shape + ' "integer levels" 12\n')
    with pytest.raises(UserError, match="bad.pbrt:2: 'levels': 12 levels make 134,217,728 triangles of 8, more than"):
        load_scene(str(path))
