"""Mitsuba's serialized meshes (app/scene/serialized.py, the `serialized` shape of
app/scene/mesh_shapes.py): the fixtures of tests/scenes/serialized.xml read back as they were
written (Mitsuba 3 reads the same files for its reference image, tests/test_reference.py), each
header and version, and every damaged file as one line naming the element and the file."""

import struct
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pathtrace.errors import UserError
from pathtrace.scene.meshes import check_mesh, read_mesh, vertex_normals
from pathtrace.scene.mitsuba import read_mitsuba_file
from pathtrace.scene.serialized import read_serialized
from tests.serialized_files import SCENES, mesh_stream, serialized_file

TORUS = read_mesh(SCENES / "torus.ply", "torus")
OCTAHEDRON = read_mesh(SCENES / "octahedron.obj", "octahedron")


def f32(a):
    return np.asarray(a, np.float32).astype(np.float64)


def test_the_fixtures_read_back_as_written():
    torus = read_serialized(SCENES / "meshes.serialized", 0, "here")
    np.testing.assert_array_equal(torus.vertices, f32(TORUS.vertices))
    np.testing.assert_array_equal(torus.faces, TORUS.faces)
    np.testing.assert_array_equal(torus.uvs, f32(TORUS.uvs))        # as stored: no v turned round
    np.testing.assert_array_equal(torus.normals, f32(vertex_normals(TORUS.vertices, TORUS.faces)))
    octahedron = read_serialized(SCENES / "meshes.serialized", 1, "here")     # its colours skipped
    np.testing.assert_array_equal(octahedron.vertices, f32(OCTAHEDRON.vertices))
    assert octahedron.normals is None and octahedron.uvs is None
    # version 3 (no name, uint32 offsets), in float64: exactly
    torus = read_serialized(SCENES / "double.serialized", 1, "here")
    np.testing.assert_array_equal(torus.vertices, TORUS.vertices)
    np.testing.assert_array_equal(torus.faces, TORUS.faces)
    assert torus.normals is None and torus.uvs is None


@pytest.mark.parametrize("version", [3, 4])
def test_shape_index_finds_its_mesh_among_many(tmp_path, version):
    path = tmp_path / "many.serialized"
    path.write_bytes(serialized_file([mesh_stream(OCTAHEDRON.vertices + k, OCTAHEDRON.faces, name=f"m{k}",
                                                  version=version, double=True) for k in range(50)], version))
    for k in (0, 1, 37, 49):
        np.testing.assert_array_equal(read_serialized(path, k, "here").vertices, OCTAHEDRON.vertices + k)


def test_the_scene_takes_each_shape_index_and_smooths_as_mitsuba():
    scene = read_mitsuba_file(SCENES / "serialized.xml")
    checker, octahedron, faceted = scene.meshes[1:4]
    assert [len(m.faces) for m in (checker, octahedron, faceted)] == [1536, 8, 1536]
    assert checker.uvs is not None and checker.normals is not None
    assert octahedron.normals is not None          # none in the file: smoothed, as Mitsuba 3 does
    assert faceted.normals is None                 # face_normals
    assert checker.file is None                    # convert writes it anew: no other format reads the file


def scene_with(tmp_path, data: bytes, index=0):
    (tmp_path / "m.serialized").write_bytes(data)
    (tmp_path / "s.xml").write_text(
        '<?xml version="1.0"?>\n<scene version="3.0.0">\n<shape type="serialized">'
        f'<string name="filename" value="m.serialized"/><integer name="shape_index" value="{index}"/>'
        '</shape>\n</scene>\n')
    return tmp_path / "s.xml"


GOOD = mesh_stream(OCTAHEDRON.vertices, OCTAHEDRON.faces)


@pytest.mark.parametrize("data,index,message", [
    (b"PLY\n" + GOOD, 0, "not a Mitsuba serialized mesh"),
    (struct.pack("<HH", 0x041C, 5) + GOOD[4:], 0, "version 5; Mitsuba 3 reads versions 3 and 4"),
    (serialized_file([GOOD, GOOD]), 2, "shape_index 2 is out of range: the file holds 2 meshes"),
    (GOOD + struct.pack("<QQI", 0, 3, 2), 1, r"the offset of mesh 1 \(3\) is not the start of a mesh"),
    (GOOD[:len(GOOD) // 2], 0, "damaged serialized mesh|ends early"),
    (GOOD[:4] + b"not zlib at all", 0, "damaged serialized mesh"),
    (GOOD[:4] + zlib.compress(struct.pack("<I", 0x1000) + b"m\0" + struct.pack("<QQ", 6, 8) + b"\0" * 24), 0,
     "the mesh ends early: 24 bytes of the 168"),
    (GOOD[:4] + zlib.compress(struct.pack("<I", 0x1000) + b"m\0" + struct.pack("<QQ", 6, 0)), 0,
     "a mesh of 0 triangles"),
    (GOOD[:4] + zlib.compress(struct.pack("<I", 0x1000) + b"m" * 5000), 0, "name is not ended"),
    (GOOD[:4] + zlib.compress(struct.pack("<I", 0x1000) + b"m\0" + struct.pack("<Q", 6)), 0, "ends within its header"),
    (GOOD[:4] + zlib.compress(struct.pack("<I", 0x1000) + b"m\0" + struct.pack("<QQ", 2**40, 8)), 0,
     "a mesh of 1099511627776 vertices"),
    (GOOD[:4] + zlib.compress(struct.pack("<I", 0x2003) + b"m\0" + struct.pack("<QQ", 10**8, 6 * 10**7)), 0,
     "would take .* MB, more than pathtrace reads"),
    (GOOD + struct.pack("<QI", 0, 99), 1, "dictionary of meshes .* is damaged: a count of 99"),
    (mesh_stream(OCTAHEDRON.vertices, OCTAHEDRON.faces + 10), 0, "face 0 refers to vertex"),
])
def test_a_damaged_file_is_one_line_naming_the_element_and_the_file(tmp_path, data, index, message):
    with pytest.raises(UserError, match=message) as e:
        read_mitsuba_file(scene_with(tmp_path, data, index))
    assert str(e.value).startswith(f"{tmp_path / 's.xml'}:3: <shape type=\"serialized\">")
    assert "m.serialized" in str(e.value) and "\n" not in str(e.value)


def test_a_missing_file_and_a_negative_index_are_refused(tmp_path):
    with pytest.raises(UserError, match="shape_index: must be in 0"):
        read_mitsuba_file(scene_with(tmp_path, GOOD, -1))
    path = scene_with(tmp_path, GOOD)
    (tmp_path / "m.serialized").unlink()
    with pytest.raises(UserError, match=r"s.xml:3: .*m.serialized"):
        read_mitsuba_file(path)


VALID = serialized_file([mesh_stream(TORUS.vertices[:40], TORUS.faces[TORUS.faces.max(axis=1) < 40], uvs=TORUS.uvs[:40],
                                     colors=TORUS.vertices[:40]), GOOD])


@settings(max_examples=300, deadline=None)
@given(damages=st.lists(st.tuples(st.sampled_from(["cut", "flip", "insert"]), st.integers(0, len(VALID) - 1),
                                  st.integers(1, 255)), min_size=1, max_size=3), index=st.integers(0, 2))
def test_a_damaged_file_reads_as_a_checked_mesh_or_one_line(tmp_path_factory, damages, index):
    """Cut short, bytes flipped or inserted: a mesh that check_mesh passes, or a UserError of one
    line; never another exception (zlib's, struct's, NumPy's) or a hang."""
    data = bytearray(VALID)
    for how, at, byte in damages:
        at = min(at, max(len(data) - 1, 0))
        if how == "cut":
            data = data[:at]
        elif how == "flip" and data:
            data[at] ^= byte
        elif how == "insert":
            data[at:at] = bytes([byte]) * 8
    path = tmp_path_factory.mktemp("damaged") / "m.serialized"
    path.write_bytes(bytes(data))
    try:
        check_mesh(*read_serialized(path, index, "here"), where="here")
    except UserError as e:
        assert str(e).startswith("here") and "\n" not in str(e)
