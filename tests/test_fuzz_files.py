"""Fuzzers of the files a scene names and of Mitsuba XML scenes (#28), beside the TOML one
(tests/test_fuzz_scenes.py), with the same bar: each case, rendered by the command line in a
batch run in a process of its own (tests/fuzz_batch.py), exits 0 with finite pixels or 1 with one
error line naming the file; no traceback, hang, foreign line or leftover file.

- Mitsuba XML: a valid scene whose attribute values are sometimes replaced by odd text (huge,
  tiny, non-finite, negative, Unicode digits, NUL, wavelength lists), whose elements are
  sometimes repeated or nested in one another, and whose ids sometimes point nowhere or back.
- Meshes (PLY ascii and binary, OBJ, STL), maps (Radiance HDR, PFM, OpenEXR) and texture images
  (PNG, JPEG, TGA, BMP): valid files cut short, with bytes flipped or inserted, or with a header
  line replaced."""

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pathtrace.io.images import write_image
from tests.test_fuzz_scenes import check_batch

ODD_TEXT = ["", "nan", "inf", "-1", "0", "1e40", "-1e40", "1e-300", "3.5e38", "²", "9" * 60, "1, 2",
            "400:0.5:1", "a\x00b", "\n", "$x", "../../x", "1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16", "0mm"]

XML = """<?xml version="1.0"?>
<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="6"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 1, 6" target="0, 0.5, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film>
  </sensor>
  <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf>
  <bsdf type="roughconductor" id="metal"><float name="alpha" value="0.2"/><string name="material" value="Au"/></bsdf>
  <texture type="bitmap" id="tiles"><string name="filename" value="t.png"/><string name="wrap_mode" value="mirror"/>
    <transform name="to_uv"><scale x="2" y="3"/></transform></texture>
  <bsdf type="mask" id="leaf"><float name="opacity" value="0.6"/>
    <bsdf type="normalmap"><ref name="normalmap" id="tiles"/><bsdf type="diffuse"><ref name="reflectance" id="tiles"/></bsdf></bsdf>
  </bsdf>
  <shape type="cube"><transform name="to_world"><translate x="-2" y="0.5" z="0"/></transform><ref id="leaf"/></shape>
  <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
  <shape type="sphere"><point name="center" x="0" y="0.5" z="0"/><float name="radius" value="1"/><ref id="metal"/></shape>
  <shape type="rectangle">
    <transform name="to_world"><rotate x="1" angle="-90"/><scale value="10"/></transform>
    <ref id="white"/>
  </shape>
  <shape type="sphere">
    <transform name="to_world"><translate x="2" y="3" z="1"/></transform>
    <float name="radius" value="0.3"/>
    <emitter type="area"><rgb name="radiance" value="20"/></emitter>
  </shape>
</scene>
"""


@st.composite
def xml_scenes(draw):
    """The valid scene with a few mutations of its values, elements and references."""
    text = XML
    values = [m for m in _attribute_values(text)]
    for _ in range(draw(st.integers(0, 3))):
        start, end = draw(st.sampled_from(values))
        odd = draw(st.sampled_from(ODD_TEXT))
        text = text[:start] + odd.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;") \
            + text[end:] if end <= len(text) else text
        values = list(_attribute_values(text))
    kind = draw(st.sampled_from(["none", "repeat", "nest", "dangling", "cycle"]))
    if kind == "repeat":
        shape = text[text.index("  <shape"):text.index("</shape>") + 8]
        text = text.replace("</scene>", shape * draw(st.integers(2, 50)) + "</scene>")
    elif kind == "nest":
        depth = draw(st.integers(2, 300))
        text = text.replace("</scene>", '<shape type="sphere">' * depth + "</shape>" * depth + "</scene>")
    elif kind == "dangling":
        text = text.replace('<ref id="white"/>', '<ref id="' + draw(st.sampled_from(["black", "x" * 5000])) + '"/>')
    elif kind == "cycle":
        text = text.replace('<bsdf type="diffuse" id="white">',
                            '<bsdf type="twosided" id="white"><ref id="white"/>').replace(
            '<rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf>', "</bsdf>", 1)
    return text


def _attribute_values(text: str):
    """(start, end) of every value="..." and x/y/z/angle="..." attribute."""
    import re
    return [(m.start(2), m.end(2)) for m in re.finditer(r'\b(value|x|y|z|angle|origin|target|up)="([^"]*)"', text)]


# 15 cases a test: three examples, each a batch of five rendered in one process (tests/fuzz_batch.py)
BATCH = 5
FUZZ = settings(max_examples=15 // BATCH, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@FUZZ
@given(texts=st.lists(xml_scenes(), min_size=BATCH, max_size=BATCH))
def test_mitsuba_scenes_render_finite_pixels_or_are_refused_in_one_line(tmp_path, texts):
    def write(folder, text):
        path = folder / "fuzzed.xml"
        path.write_text(text)
        (folder / "t.png").write_bytes(VALID["tex.png"])
        return path, ["t.png"], text, None
    check_batch(tmp_path, texts, write)

def _valid_files() -> dict:
    """Small valid files of each format, as bytes."""
    from io import BytesIO

    import trimesh
    from plyfile import PlyData, PlyElement

    vertices = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1], [0, 1, 0]], np.float32)
    faces = np.array([[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]])
    files = {}
    v = np.array([tuple(p) for p in vertices], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    f = np.array([(list(t),) for t in faces], dtype=[("vertex_indices", "i4", (3,))])
    for name, text in (("ascii.ply", True), ("binary.ply", False)):
        out = BytesIO()
        PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")], text=text).write(out)
        files[name] = out.getvalue()
    files["mesh.obj"] = ("".join(f"v {x} {y} {z}\n" for x, y, z in vertices)
                         + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)).encode()
    files["mesh.stl"] = trimesh.Trimesh(vertices, faces, process=False).export(file_type="stl")
    folder = Path(tempfile.mkdtemp())
    image = np.random.default_rng(3).uniform(0, 2, (8, 16, 3)).astype(np.float32)
    for name in ("map.hdr", "map.pfm", "map.exr"):
        write_image(folder / name, image, what="test")
        files[name] = (folder / name).read_bytes()
    from PIL import Image
    texels = np.random.default_rng(4).integers(0, 256, (6, 5, 3)).astype(np.uint8)
    for name in ("tex.png", "tex.jpg", "tex.tga", "tex.bmp"):
        Image.fromarray(texels).save(folder / name)
        files[name] = (folder / name).read_bytes()
    return files


VALID = _valid_files()


@st.composite
def damaged_files(draw):
    """(name, bytes): a valid file with one to three damages."""
    name = draw(st.sampled_from(sorted(VALID)))
    data = bytearray(VALID[name])
    for _ in range(draw(st.integers(1, 3))):
        how = draw(st.sampled_from(["cut", "flip", "insert", "header"]))
        at = draw(st.integers(0, max(len(data) - 1, 0)))
        if how == "cut":
            data = data[:at]
        elif how == "flip" and data:
            data[at] ^= draw(st.integers(1, 255))
        elif how == "insert":
            data[at:at] = draw(st.sampled_from([b"\x00", b"\n", b"nan ", b"-1 ", b"99999999999 ", b"\xff" * 8]))
        elif how == "header":
            lines = bytes(data).split(b"\n")
            k = draw(st.integers(0, min(len(lines), 12) - 1))
            lines[k] = draw(st.sampled_from([b"", b"element vertex 99999999999", b"format binary_big_endian 1.0",
                                             b"-Y 99999 +X 99999", b"PF", b"1e40 1e40 1e40", b"f 1 2 999"]))
            data = bytearray(b"\n".join(lines))
    return name, bytes(data)


@FUZZ
@given(batch=st.lists(damaged_files(), min_size=BATCH, max_size=BATCH))
def test_damaged_meshes_and_maps_render_finite_pixels_or_are_refused_in_one_line(tmp_path, batch):
    def write(folder, damaged):
        name, data = damaged
        (folder / name).write_bytes(data)
        material = '{ type = "diffuse", rho_d = 0.5 }'
        if name.startswith("map"):
            scene = f'[environment]\nmap = "{name}"\n[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = {material}\n'
        elif name.startswith("tex"):
            material = f'{{ type = "diffuse", rho_d = {{ type = "bitmap", file = "{name}" }}, opacity = {{ type = "bitmap", file = "{name}" }} }}'
            scene = f'[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = {material}\n'
        else:
            scene = f'[camera]\neye = [0, 2, 5]\nlook_at = [0, 0, 0]\n[[meshes]]\nfile = "{name}"\nmaterial = {material}\n'
        path = folder / "fuzzed.toml"
        path.write_text(scene)
        return path, [name], f"{name}: {data[:200]!r}...", name
    check_batch(tmp_path, batch, write)
