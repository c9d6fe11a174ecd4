"""Loading meshes (app/scene/meshes.py) in each format, with transforms, and every bad file
reported in one line naming the file."""

import numpy as np
import pytest

from pathtrace.cli.main import main
from pathtrace.errors import UserError
from pathtrace.scene import load_scene
from pathtrace.scene.meshes import read_mesh
from tests.commands import in_process
from tests.geometry import cube

QUAD_OBJ = """# a unit quad in the x-y plane, facing +z, with normals, as one polygon
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vn 0 0 1
f 1//1 2//1 3//1 4//1
"""


def write_ply(path, vertices, faces, normals=None, ascii=False):
    from plyfile import PlyData, PlyElement
    fields = [("x", "f4"), ("y", "f4"), ("z", "f4")] + ([("nx", "f4"), ("ny", "f4"), ("nz", "f4")] if normals is not None else [])
    rows = [tuple(v) + (tuple(n) if normals is not None else ()) for v, n in zip(vertices, normals if normals is not None else vertices)]
    v = np.array(rows, dtype=fields)
    f = np.array([(list(t),) for t in faces], dtype=[("vertex_indices", "O")])
    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")], text=ascii).write(str(path))


@pytest.mark.parametrize("ascii", [False, True])
def test_ply_with_normals(tmp_path, ascii):
    v, f = cube()
    write_ply(tmp_path / "c.ply", v, f, normals=v / np.linalg.norm(v, axis=1, keepdims=True), ascii=ascii)
    vertices, faces, normals, _ = read_mesh(tmp_path / "c.ply", "test")
    np.testing.assert_allclose(vertices, v)
    assert faces.shape == (12, 3) and normals is not None


def test_obj_polygons_are_triangulated_with_their_normals(tmp_path):
    (tmp_path / "q.obj").write_text(QUAD_OBJ)
    vertices, faces, normals, _ = read_mesh(tmp_path / "q.obj", "test")
    assert faces.shape == (2, 3)
    corners = vertices[faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(n[:, 2] > 0)                 # the winding kept: front faces +z
    np.testing.assert_allclose(normals, np.tile([0, 0, 1.0], (len(vertices), 1)))


@pytest.mark.parametrize("suffix", [".stl", ".glb"])
def test_stl_and_glb(tmp_path, suffix):
    import trimesh
    v, f = cube()
    trimesh.Trimesh(v, f, process=False).export(str(tmp_path / f"c{suffix}"))
    vertices, faces, _, _ = read_mesh(tmp_path / f"c{suffix}", "test")
    assert len(faces) == 12
    corners = vertices[faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(np.sum(n * corners.mean(axis=1), axis=1) > 0)   # still facing out


def scene_with_mesh(tmp_path, mesh_toml):
    (tmp_path / "q.obj").write_text(QUAD_OBJ)
    path = tmp_path / "s.toml"
    path.write_text(f"""[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[[meshes]]
file = "q.obj"
material = {{ type = "diffuse", rho_d = 0.5 }}
{mesh_toml}
""")
    return path


def test_transform_applies_scale_then_rotate_then_translate(tmp_path):
    scene = load_scene(str(scene_with_mesh(tmp_path, 'scale = 2\nrotate = [0, 0, 1, 90]\ntranslate = [10, 0, 0]')))
    # corner (1, 0, 0): scaled to (2, 0, 0), turned to (0, 2, 0), moved to (10, 2, 0)
    v = scene.meshes[0].vertices
    assert np.any(np.all(np.abs(v - [10, 2, 0]) < 1e-5, axis=1))
    assert scene.meshes[0].name == "q"


def test_matrix_and_mirroring_keep_the_front(tmp_path):
    scene = load_scene(str(scene_with_mesh(tmp_path, 'matrix = [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]')))
    m = scene.meshes[0]
    corners = m.vertices[m.faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(n[:, 2] > 0)


def test_degenerate_triangles_are_dropped_with_a_count(tmp_path, capsys):
    write_ply(tmp_path / "d.ply", [[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], [[0, 1, 2], [0, 1, 3], [1, 1, 2]])
    _, faces, _, _ = read_mesh(tmp_path / "d.ply", "test")
    assert len(faces) == 1
    assert "dropped 2 degenerate triangle(s) of 3" in capsys.readouterr().err


BAD = [
    ("garbage.ply", b"ply\nformat nonsense\n", "not a readable PLY mesh"),
    ("garbage.obj", b"\x00\x01\x02 not an obj", "no triangles"),
    ("empty.stl", b"", "no triangles"),
    ("mesh.xyz", b"1 2 3", "unknown mesh format"),
    ("short.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 3\n", r"line 3: face corner 3 names a vertex the file does not have \(2 so far"),
    ("word.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "line 4: face corner 'x' is not a vertex index"),
    ("back.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "line 4: face corner -4"),
    ("vt.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
     r"line 5: face corner '2/2' names a texture coordinate \(vt\) the file does not have \(1 so far"),
    ("vn.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//-2\n",
     r"line 5: face corner '3//-2' names a normal \(vn\) the file does not have \(1 so far"),
    ("slashes.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n",
     "line 4: face corner '1/1/1/1' is not v, v/vt, v//vn or v/vt/vn indices"),
    ("lead.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 /3\n", "line 4: face corner '/3' is not a vertex index"),
    ("two.obj", b"v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", r"line 2: a vertex \(v\) needs three coordinates, got 2"),
    ("zero.obj", b"v 0 0 0\nv 1 0 zero\nv 0 1 0\nf 1 2 3\n", "line 2: 'zero' is not a number"),
    ("first.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\nv 0 x 0\nvt 1\nf 1/1 2/1 3/4\n",
     "line 4: face corner 9 names a vertex"),
    ("earlier.obj", b"v 0 0 0\nv 1 0 0\nvn 0 0 y\nv 0 1 0\nf 1 2 4\n", "line 3: 'y' is not a number"),
    ("list.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty list uchar float x\nproperty float y\n"
                 b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                 b"1 0 0 0\n1 1 0 0\n1 0 1 0\n3 0 1 2\n", "the PLY vertex property 'x' must be a number, not a list"),
]


@pytest.mark.parametrize("name,content,message", BAD)
def test_bad_files_give_one_line(tmp_path, name, content, message):
    (tmp_path / name).write_bytes(content)
    with pytest.raises(UserError, match=message) as e:
        read_mesh(tmp_path / name, "meshes[0].file")
    assert str(tmp_path / name) in str(e.value) and "\n" not in str(e.value)


def test_nan_vertices_and_bad_indices(tmp_path):
    write_ply(tmp_path / "n.ply", [[0, 0, 0], [np.nan, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    with pytest.raises(UserError, match="vertex 1 is not finite"):
        read_mesh(tmp_path / "n.ply", "test")
    (tmp_path / "i.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(UserError, match="line 4: face corner 9 names a vertex"):
        read_mesh(tmp_path / "i.obj", "test")
    (tmp_path / "neg.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n")     # relative indices
    assert read_mesh(tmp_path / "neg.obj", "test")[1].tolist() == [[0, 1, 2]]
    write_ply(tmp_path / "i.ply", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 7]])
    with pytest.raises(UserError, match="face 0 refers to vertex"):
        read_mesh(tmp_path / "i.ply", "test")


def test_cli_names_the_scene_field_and_mesh_file(tmp_path, capsys):
    path = scene_with_mesh(tmp_path, "")
    path.write_text(path.read_text().replace('"q.obj"', '"missing.ply"'))
    assert main(["render", str(path), "-o", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "meshes[0].file" in err[0] and "missing.ply' does not exist" in err[0] and "mesh file '" in err[0]


def test_a_gltf_buffer_that_is_a_fifo_is_refused_without_opening_it(tmp_path):
    """trimesh opened a glTF's external buffer however it was made: a FIFO hung the load."""
    import os
    os.mkfifo(tmp_path / "buf.bin")
    (tmp_path / "m.gltf").write_text('{"asset": {"version": "2.0"}, "buffers": [{"uri": "buf.bin", "byteLength": 36}]}')
    with pytest.raises(UserError, match=r"buffers\[0\]: file '.*buf.bin' is not a regular file"):
        read_mesh(tmp_path / "m.gltf", "meshes[0].file")


def test_a_mesh_librarys_own_slip_is_not_quoted(tmp_path):
    """trimesh ends on a glTF whose primitive names a missing accessor in an UnboundLocalError
    about its own variables (a new user's run, 2026-12-03): the line says the file is malformed."""
    (tmp_path / "m.gltf").write_text('{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":5}}]}]}')
    with pytest.raises(UserError) as e:
        read_mesh(tmp_path / "m.gltf", "meshes[0].file")
    assert str(e.value).endswith("m.gltf: not a readable GLTF mesh (malformed)"), str(e.value)


def test_nan_indices_and_huge_coordinates_print_nothing_but_our_line(tmp_path):
    """NumPy's own warnings reached the terminal before pathtrace's line (a NaN face index cast
    to int, a cross product of 1e17 coordinates squared in float32)."""
    (tmp_path / "n.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 1\nproperty list uchar float vertex_indices\n"
                                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 nan\n")
    (tmp_path / "big.obj").write_text("v 0 0 0\nv 1e17 0 0\nv 0 1e17 0\nf 1 2 3\n")
    for name, status in (("n.ply", 1), ("big.obj", 0)):
        scene = tmp_path / f"{name}.toml"
        scene.write_text(f'[[meshes]]\nfile = "{name}"\nmaterial = {{ type = "diffuse", rho_d = 0.5 }}\n')
        r = in_process("render", scene, "-o", tmp_path / "o.exr", "--size", "8x6", "--spp", "1", "-q")   # warnings shown
        assert r.returncode == status and "Warning" not in r.stderr, r.stderr
    assert "whole numbers" in in_process("render", tmp_path / "n.ply.toml", "-o", tmp_path / "o.exr").stderr


@pytest.mark.parametrize("order", ["<", ">"])
def test_binary_ply_read_as_views_equals_plyfiles_reading(tmp_path, order):
    """The NumPy reader of binary triangle PLYs (both byte orders, extra properties, double
    coordinates, ushort counts) gives what plyfile gives; a quad sends the file to plyfile."""
    from plyfile import PlyData, PlyElement

    from pathtrace.scene.meshes import _read_binary_triangles
    rng = np.random.default_rng(3)
    v = np.zeros(5, [("x", "f8"), ("y", "f8"), ("z", "f8"), ("confidence", "f4"), ("nx", "f4"), ("ny", "f4"),
                     ("nz", "f4"), ("s", "f4"), ("t", "f4")])
    for name in v.dtype.names:
        v[name] = rng.random(5)
    faces = np.array([([0, 1, 2],), ([1, 3, 2],), ([2, 3, 4],)], [("vertex_indices", "i4", (3,))])
    path = tmp_path / "m.ply"
    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(faces, "face", len_types={"vertex_indices": "u2"})],
            byte_order=order).write(str(path))
    assert _read_binary_triangles(path.read_bytes(), path) is not None
    mesh = read_mesh(path, "test")
    assert np.allclose(mesh.vertices, np.column_stack([v["x"], v["y"], v["z"]]))
    assert np.allclose(mesh.normals, np.column_stack([v["nx"], v["ny"], v["nz"]]))
    assert np.allclose(mesh.uvs, np.column_stack([v["s"], v["t"]]))
    assert np.array_equal(mesh.faces, [[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    quads = np.array([([0, 1, 3, 2],)], [("vertex_indices", "i4", (4,))])
    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(quads, "face")], byte_order=order).write(str(path))
    assert _read_binary_triangles(path.read_bytes(), path) is None
    assert np.array_equal(read_mesh(path, "test").faces, [[0, 1, 3], [0, 3, 2]])


def test_a_binary_ply_shorter_than_its_header_says_is_refused(tmp_path):
    path = tmp_path / "short.ply"
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 1099511627776\nproperty float x\n"
                     b"property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                     b"end_header\n" + b"\0" * 64)
    with pytest.raises(UserError, match="^scene.xml:3: filename: .*short.ply: the PLY file holds 64 bytes of data "
                                        "where its header claims"):      # the field that names it first
        read_mesh(path, "scene.xml:3: filename")



# --- OBJ, read by app/scene/obj.py ---------------------------------------------------------

def corner_rows(mesh):
    """A mesh as its triangles' corners (position, then uv and normal where it has them), each
    triangle turned to start at its least corner, sorted: equal for two meshes that differ only
    in the order of their vertices, of their triangles and of a triangle's corners (kept in turn)."""
    vertices, faces, normals, uvs = mesh
    columns = [vertices[faces]] + [a[faces] for a in (uvs, normals) if a is not None]
    corners = np.round(np.concatenate(columns, axis=2), 6).reshape(len(faces), -1)
    width = corners.shape[1] // 3
    return np.array(sorted(min(tuple(np.roll(c, -k * width)) for k in range(3)) for c in corners))


def trimesh_obj(path):
    """The mesh trimesh's OBJ reader makes of a file, as pathtrace read OBJ files before its own
    reader (its parts joined, vt's v flipped to Mitsuba's convention)."""
    import io

    import trimesh.exchange.obj as obj

    from pathtrace.scene.meshes import _concatenate, _trimesh_uvs
    loaded = obj.load_obj(io.StringIO(path.read_text()), skip_materials=True)
    parts = list(loaded.get("geometry", {}).values()) if "geometry" in loaded else [loaded]
    return _concatenate([(p.get("vertices"), p.get("faces"), p.get("vertex_normals"), _trimesh_uvs(p.get("visual")))
                         for p in parts])


FORMS = ("{v}", "{v}/{t}", "{v}//{n}", "{v}/{t}/{n}")


def random_obj(seed: int) -> str:
    """An OBJ file of random v, vt and vn (in fixed point or not, with colours or w or not) and
    faces of 3 to 6 distinct corners, all of one form or of mixed forms, with indices from 1 or
    negative ones, and other statements: as trimesh reads it right (every v, vt and vn before
    the faces, as trimesh counts negative indices back from the file's last; where forms are
    mixed, the first face a v/vt/vn triangle and no usemtl, so that trimesh reads each face line
    by itself)."""
    rng = np.random.default_rng(seed)
    number = rng.choice(["{:.6f}", "{!r}", "{:.3g}", "{:.4f}"])
    negative, mixed = rng.random() < 0.4, rng.random() < 0.4
    counts = dict(zip("vtn", rng.integers(6, 40, 3)))
    colours, w = rng.random() < 0.2, rng.random() < 0.2
    v = [f"v {' '.join(number.format(float(x)) for x in p)}" + (" 0.5 0.25 1" if colours else "")
         for p in rng.uniform(-5, 5, (counts["v"], 3))]
    t = [f"vt {' '.join(number.format(float(x)) for x in p)}" + (" 0" if w else "") for p in rng.uniform(0, 1, (counts["t"], 2))]
    n = [f"vn {' '.join(number.format(float(x)) for x in p)}" for p in rng.normal(size=(counts["n"], 3))]
    form = rng.choice(FORMS)
    faces = []
    for k in range(int(rng.integers(2, 30))):
        size = 3 if (mixed and k == 0) or rng.random() < 0.4 else int(rng.integers(3, 7))
        corner = FORMS[3] if mixed and k == 0 else rng.choice(FORMS) if mixed else form
        picks = {key: rng.choice(counts[key], size, replace=False) for key in "vtn"}
        faces.append("f " + " ".join(corner.format(**{key: int(picks[key][j]) - counts[key] if negative and rng.random() < 0.5
                                                     else int(picks[key][j]) + 1 for key in "vtn"}) for j in range(size)))
        if not mixed and rng.random() < 0.15:
            faces.append(f"usemtl m{int(rng.integers(3))}")
    head = ["# random", "mtllib none.mtl", "o thing"]
    return "\n".join(head + v + t + n + ["g part", "s 1"] + faces) + "\n"


@pytest.mark.parametrize("seed", range(40))
def test_obj_reads_as_trimesh_read_it(tmp_path, seed):
    """The OBJ reader against trimesh's, which pathtrace used before: the same triangles, each
    corner with the same position, uv and normal, on quads, polygons, negative indices, missing
    vt or vn and mixed forms; vertices split where a v has another vt or vn in another face,
    and none that no face uses."""
    from pathtrace.scene.meshes import check_mesh
    path = tmp_path / "random.obj"
    path.write_text(random_obj(seed))
    ours = read_mesh(path, "test")
    theirs = check_mesh(*trimesh_obj(path), where="trimesh")
    assert (ours.uvs is None, ours.normals is None) == (theirs.uvs is None, theirs.normals is None)
    a, b = corner_rows(ours), corner_rows(theirs)
    assert a.shape == b.shape and np.allclose(a, b, atol=1e-6)
    assert len(np.unique(ours.faces)) == len(ours.vertices)


def test_obj_forms_split_vertices_and_fans():
    """Each distinct (v, vt, vn) a vertex, in the order of the v lines; a quad a fan about its
    first corner; vt's v flipped; a face of fewer than three corners skipped."""
    from pathtrace.scene.obj import parse_obj
    text = (b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.25\n"
            b"vn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf 1/5/1 3/3/1 4/4/1\nf 1/1/1 2/2/1\n")
    vertices, faces, normals, uvs = parse_obj(text, "test")
    assert vertices.tolist() == [[0, 0, 0], [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]   # v 1 twice, v 5 unused
    assert uvs.tolist() == [[0, 1], [0.5, 0.75], [1, 1], [1, 0], [0, 0]]
    assert faces.tolist() == [[0, 2, 3], [0, 3, 4], [1, 3, 4]]
    assert normals.tolist() == [[0, 0, 1]] * 5
    # where some corner has no vt (or vn), the mesh has none
    vertices, faces, normals, uvs = parse_obj(text.replace(b"f 1/5/1 3/3/1", b"f 1//1 3//1"), "test")
    assert uvs is None and normals is not None and faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 2, 3]]


def test_obj_as_blender_writes_it_is_the_torus_it_was_written_from(tmp_path):
    """The benchmark's OBJ torus (each point once, the uv seams doubled in vt only, v/vt/vn
    corners) reads as the torus: its points split where the seams give them two uvs."""
    from pathtrace.bench.scenes import torus, torus_obj
    (tmp_path / "t.obj").write_text(torus_obj())
    mesh = read_mesh(tmp_path / "t.obj", "test")
    points, normals, uvs, faces = torus()
    assert len(mesh.vertices) == len(points) == 33 * 17 and len(mesh.faces) == len(faces)
    assert np.allclose(corner_rows(mesh), corner_rows((points, faces, normals, uvs)), atol=1e-4)


def test_obj_negative_indices_count_back_from_what_was_read_so_far():
    """-1 is the last vertex read before the face (the OBJ format's rule; trimesh's reader
    counted back from the file's last)."""
    from pathtrace.scene.obj import parse_obj
    vertices, faces, _, _ = parse_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                                      b"v 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\nf 1 2 -1\n", "test")
    assert vertices[faces].tolist() == [[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1], [1, 0, 1], [0, 1, 1]],
                                        [[0, 0, 0], [1, 0, 0], [0, 1, 1]]]


def test_an_obj_face_of_fewer_than_three_corners_is_skipped_with_a_warning_each_read(tmp_path, capsys):
    """As a file cut short ends: the face is skipped (as trimesh's reader skipped it), and said so
    on every read (the mesh is not kept for the next, app/scene/mesh_cache.py)."""
    from pathtrace.scene import mesh_cache
    path = tmp_path / "cut.obj"
    path.write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2\nf 2 4")
    with mesh_cache.reading({}) as found:
        mesh = read_mesh(path, "here")
    assert mesh.faces.tolist() == [[0, 1, 2]] and found == {}
    assert capsys.readouterr().err == f"pathtrace: warning: here: {path}: line 6: skipped 2 face(s) of fewer " \
                                      "than three corners\n"


def test_obj_layout_as_editors_write_it():
    """Comments, indentation, continued lines, CRLF, a byte order mark, other statements, colours
    after a v, w after a vt and a vt of u alone (v = 0) are read as the format has them."""
    from pathtrace.scene.obj import parse_obj
    text = (b"\xef\xbb\xbf# made by hand\r\nmtllib m.mtl\r\no a # name\r\n  v 0 0 0 1 0 0\r\n\tv 1 0 \\\r\n 0\r\n"
            b"v 0 1 0 # third\r\nvt 0.25\r\nvt 1 0 0\r\nvt 0 1 0.5\r\ns off\r\nusemtl x\r\nvp 1 2\r\nl 1 2\r\n"
            b"f 1/1 2/2 \\\n 3/3 # a triangle\r\n")
    vertices, faces, normals, uvs = parse_obj(text, "test")
    assert vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]] and faces.tolist() == [[0, 1, 2]]
    assert uvs.tolist() == [[0.25, 1], [1, 1], [0, 0]] and normals is None


def test_obj_decimals_read_as_float_reads_them():
    """Values in fixed point, read by NumPy's integer reader and a power of ten, equal float()'s
    to the last bit; values of any other form (exponents, many digits, nan, integers) are read
    by float()."""
    from pathtrace.scene.obj import _decimals, _tokens, parse_obj
    rng = np.random.default_rng(7)
    fixed = [f"{x:.{p}f}" for x, p in zip(rng.uniform(-1e4, 1e4, 3000) * 10.0 ** -rng.integers(0, 8, 3000),
                                          rng.integers(1, 10, 3000))] + ["+.5", "-7.", "-0.000"]
    text = np.frombuffer(" ".join(fixed).encode() + b"\n", np.uint8)
    values = _decimals(text, *_tokens(text))
    assert values is not None and np.array_equal(values, [float(w) for w in fixed])
    for other in (["1e-5"], ["0.000000000000000001"], ["nan"], ["12"], ["1.2.3"], ["1-2"]):
        text = np.frombuffer(" ".join(fixed[:5] + other).encode() + b"\n", np.uint8)
        assert _decimals(text, *_tokens(text)) is None
    words = fixed[:297] + ["1e-5", "0.000000000000000001", "12"]
    obj = "".join(f"v {' '.join(words[k:k + 3])}\n" for k in range(0, len(words), 3))
    obj += "f " + " ".join(str(k + 1) for k in range(len(words) // 3)) + "\n"
    vertices = parse_obj(obj.encode(), "test")[0]
    assert np.array_equal(vertices, np.array([float(w) for w in words]).reshape(-1, 3))


def read_ahead_in(way: str, monkeypatch):
    """MeshFiles set to read every file ahead, however small, in threads, or every OBJ file in
    processes."""
    from pathtrace.scene.meshes import MeshFiles
    if way == "threads":
        monkeypatch.setattr(MeshFiles, "LARGE", 0)
    else:
        monkeypatch.setattr(MeshFiles, "MANY", 1)
        monkeypatch.setattr(MeshFiles, "PROCESS_BYTES", 0)
        monkeypatch.setattr(MeshFiles, "PROCESS_CORES", 1)


@pytest.mark.parametrize("way", ["threads", "processes"])
def test_mesh_files_hand_out_what_read_mesh_reads_in_the_order_asked(tmp_path, monkeypatch, capsys, way):
    """MeshFiles, read ahead in threads or in processes, hands out each file as read_mesh reads
    it, with its warning or problem line when it is asked for: in the order asked, the first bad
    file in file order the one reported; a file read ahead under another `where` than asked for
    speaks of the one asked for."""
    from pathtrace.bench.scenes import torus_obj
    from pathtrace.scene.meshes import MeshFiles
    read_ahead_in(way, monkeypatch)
    paths = [tmp_path / f"m{k}.obj" for k in range(9)]
    for k, path in enumerate(paths):
        path.write_text(torus_obj(8 + k, 4) + ("f 1 1 2\n" if k in (1, 3) else "f 1 2 999999\n" if k in (6, 7) else ""))
    expected = [read_mesh(path, "first") for path in paths[:6]]
    capsys.readouterr()
    with MeshFiles([(path, f"shape {k}") for k, path in enumerate(paths)]) as files:
        for k in range(6):
            mesh = files.read(paths[k], f"shape {k}")
            assert all(np.array_equal(a, b) for a, b in zip(mesh, expected[k]))
        assert [line.split(":")[2] for line in capsys.readouterr().err.splitlines()] == [" shape 1", " shape 3"]
        with pytest.raises(UserError, match=r"^shape 6: .*m6.obj: line \d+: face corner 999999") as e:
            files.read(paths[6], "shape 6")
        assert "\n" not in str(e.value)
    with MeshFiles([(paths[7], "a guess"), (paths[1], "a guess")]) as files:
        with pytest.raises(UserError, match="^shape 7: "):
            files.read(paths[7], "shape 7")
        files.read(paths[1], "shape 1")
    assert capsys.readouterr().err.startswith("pathtrace: warning: shape 1: ")


def test_mesh_files_on_two_cores_read_the_first_half_here(tmp_path, monkeypatch):
    """On fewer than PROCESS_CORES cores, the later half of the OBJ files go to one other process
    and this one reads the first half itself: each file as read_mesh reads it. A file named in
    both halves is read here (the process answers its share at once, and this one would wait
    for all of it at that file); a later half of fewer than SHARE_BYTES goes to no process."""
    import pathtrace.scene.mesh_processes as mesh_processes
    from pathtrace.bench.scenes import torus_obj
    from pathtrace.scene.meshes import MeshFiles
    monkeypatch.setattr(MeshFiles, "MANY", 1)
    monkeypatch.setattr(MeshFiles, "PROCESS_BYTES", 0)
    monkeypatch.setattr(MeshFiles, "PROCESS_CORES", 3)
    monkeypatch.setattr(MeshFiles, "SHARE_BYTES", 0)
    shares = []

    class Recorded(mesh_processes.Reading):
        def __init__(self, requests, processes):
            shares.append(([path for path, _ in requests], processes))
            super().__init__(requests, processes)
    monkeypatch.setattr(mesh_processes, "Reading", Recorded)
    paths = [tmp_path / f"m{k}.obj" for k in range(5)]
    for k, path in enumerate(paths):
        path.write_text(torus_obj(8 + k, 4))
    named = paths + [paths[0]]                   # the first file named again, in the later half
    with MeshFiles() as files:
        files.workers = 2
        files.add([(path, "shape") for path in named])
        assert shares == [(paths[3:], 1)]
        for path in named:
            assert all(np.array_equal(a, b) for a, b in zip(files.read(path, "shape"), read_mesh(path, "shape")))
        # each answered by the process (one that fails answers None, and its files are read here)
        assert all(future.result()[0] is not None for future in files.processes.futures)
    monkeypatch.setattr(MeshFiles, "SHARE_BYTES", sum(p.stat().st_size for p in paths[2:]) + 1)
    with MeshFiles() as files:
        files.workers = 2
        files.add([(path, "shape") for path in paths])
        assert files.processes is None and len(shares) == 1


def test_mesh_files_whose_processes_fail_are_read_here(tmp_path, monkeypatch):
    """A reading process that cannot start (or dies) leaves its files to this one: the same
    meshes, nothing else said."""
    import pathtrace.scene.mesh_processes as mesh_processes
    from pathtrace.bench.scenes import torus_obj
    from pathtrace.scene.meshes import MeshFiles
    read_ahead_in("processes", monkeypatch)
    paths = [tmp_path / f"m{k}.obj" for k in range(4)]
    for k, path in enumerate(paths):
        path.write_text(torus_obj(8 + k, 4))
    monkeypatch.setattr(mesh_processes.sys, "executable", str(tmp_path / "no-python"))
    with MeshFiles([(path, "shape") for path in paths]) as files:
        for path in paths:
            assert all(np.array_equal(a, b) for a, b in zip(files.read(path, "shape"), read_mesh(path, "shape")))


def test_reading_processes_load_numpy_with_one_blas_thread(tmp_path, monkeypatch):
    """The reading processes start with OPENBLAS_NUM_THREADS=1, whatever this process has: 16 of
    them each starting an OpenBLAS thread per core slowed the H200 machine's reading by a third."""
    import subprocess
    import pathtrace.scene.mesh_processes as mesh_processes
    from pathtrace.bench.scenes import torus_obj
    from pathtrace.scene.meshes import MeshFiles
    read_ahead_in("processes", monkeypatch)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")
    paths = [tmp_path / f"m{k}.obj" for k in range(2)]
    for path in paths:
        path.write_text(torus_obj(8, 4))
    started = []

    def popen(*args, **kwargs):
        started.append(kwargs["env"])
        return subprocess.Popen(*args, **kwargs)
    monkeypatch.setattr(mesh_processes.subprocess, "Popen", popen)
    with MeshFiles([(path, "shape") for path in paths]) as files:
        for path in paths:
            files.read(path, "shape")
    assert started and all(env["OPENBLAS_NUM_THREADS"] == "1" for env in started)


def test_mesh_files_whose_answers_fail_here_are_read_here_without_waiting(tmp_path, monkeypatch):
    """An error in this process while it takes a reading process's answers (here in noting the
    files' stamps) leaves none of the reads waiting: their files are read here."""
    import threading
    import pathtrace.scene.mesh_processes as mesh_processes
    from pathtrace.bench.scenes import torus_obj
    from pathtrace.scene.meshes import MeshFiles
    read_ahead_in("processes", monkeypatch)
    paths = [tmp_path / f"m{k}.obj" for k in range(4)]
    for k, path in enumerate(paths):
        path.write_text(torus_obj(8 + k, 4))

    def failing(files):
        raise MemoryError("noting")
    monkeypatch.setattr(mesh_processes, "noted", failing)
    meshes = []

    def read():
        with MeshFiles([(path, "shape") for path in paths]) as files:
            meshes.extend(files.read(path, "shape") for path in paths)
    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(120)
    assert not reader.is_alive() and len(meshes) == len(paths)
    for mesh, path in zip(meshes, paths):
        assert all(np.array_equal(a, b) for a, b in zip(mesh, read_mesh(path, "shape")))


@pytest.mark.parametrize("way", ["threads", "processes"])
@pytest.mark.parametrize("kind", ["xml", "pbrt", "toml"])
def test_a_scene_of_many_mesh_files_names_its_first_bad_one(tmp_path, monkeypatch, kind, way):
    """Each reader reads its scene's mesh files ahead (MeshFiles) and still reports the first
    bad file in file order, in one line; a scene of good files has its meshes in file order,
    and the scene's cache knows them: a file changed after is read again."""
    import pathtrace.scene.read_cache as read_cache
    from pathtrace.scene.meshes import write_ply
    read_ahead_in(way, monkeypatch)
    monkeypatch.setenv("PATHTRACE_SCENE_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(read_cache, "MIN_SECONDS", 0)
    v, f = cube()
    suffix = "ply" if kind == "pbrt" else "obj"
    names = [f"m{k}.{suffix}" for k in range(6)]
    for k, name in enumerate(names):
        if suffix == "ply":
            write_ply(tmp_path / name, np.asarray(v, float) + k, np.asarray(f))
        else:
            (tmp_path / name).write_text("".join(f"v {x + k} {y} {z}\n" for x, y, z in v)
                                         + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f))
    scene = tmp_path / f"scene.{kind}"
    if kind == "xml":
        scene.write_text('<scene version="3.0.0">' + "".join(f'<shape type="obj"><string name="filename" value="{n}"/>'
                                                             '</shape>' for n in names) + "</scene>")
    elif kind == "pbrt":
        scene.write_text('WorldBegin\nMaterial "diffuse"\n' + "".join(f'Shape "plymesh" "string filename" "{n}"\n'
                                                                      for n in names))
    else:
        scene.write_text("".join(f'[[meshes]]\nfile = "{n}"\nmaterial = {{ type = "diffuse", rho_d = 0.5 }}\n'
                                 for n in names))
    s = load_scene(str(scene))
    assert any((tmp_path / "cache").iterdir())
    assert [m.name for m in s.meshes] == [f"m{k}" for k in range(6)]
    assert [float(m.vertices[:, 0].min()) for m in s.meshes] == [float(np.min(v, axis=0)[0]) + k for k in range(6)]
    for k in (4, 2):
        (tmp_path / names[k]).write_bytes(b"ply\nformat nonsense\n" if suffix == "ply" else b"v 0 0 0\nf 1 2 3\n")
    with pytest.raises(UserError, match=r"m2\.") as e:
        load_scene(str(scene))
    assert "m4." not in str(e.value) and "\n" not in str(e.value)
