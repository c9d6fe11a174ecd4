"""Textures: the kernels' lookups against NumPy versions of the same definitions (sRGB decoding,
wrap modes, nearest and bilinear filtering, the uv transform, the combining types), a material's
textured parameters, texture coordinates from every mesh format, and bad texture input as one
line. Every type's kernel values against its host mean and bounds are in
tests/test_texture_conformance.py; whole images against Mitsuba 3 in test_reference.py
(tests/scenes/textures.xml)."""

import zlib

import numpy as np
import pytest
from PIL import Image as PILImage

from pathtrace.errors import UserError
from pathtrace.device.features import Features
from pathtrace.materials import Material, MaterialTable
from pathtrace.materials.bsdf import PBRT_PERTURBATION
from pathtrace.scene.meshes import read_mesh
from pathtrace.scene.mitsuba import read_mitsuba_file
from pathtrace.textures import TEXTURES, Image, Texture, compile_textures, read_image
from pathtrace.textures.bitmap import srgb_to_linear
from pathtrace.device.types import MATERIAL
from tests.test_mitsuba import SPHERE, write

ALL_TEXTURES = Features(textures=tuple(TEXTURES))

SOURCE = """
kernel void lookup_texture(const global Texture *textures, const global uchar *texels, int index,
                           const global float2 *uv, global float4 *out)
{
    SceneData sc;
    sc.textures = textures;
    sc.texels = texels;
    int i = get_global_id(0);
    out[i] = (float4)(eval_texture(&sc, index, uv[i]), 0.0f);
}

kernel void shade(const global Material *materials, const global TextureBinding *bindings,
                  const global Texture *textures, const global uchar *texels,
                  const global float2 *uv, global Material *out)
{
    SceneData sc;
    sc.bindings = bindings;
    sc.textures = textures;
    sc.texels = texels;
    int i = get_global_id(0);
    Material m = materials[0];
    apply_textures(&sc, &m, uv[i]);
    out[i] = m;
}
"""


def texture(kind, **params):
    return Texture(kind, TEXTURES[kind].complete(params))


def lookup(kernels, tex, uv):
    """The kernel's values of `tex` at uv (N, 2)."""
    tables = compile_textures([[("", 0, 3, tex)]])
    out = np.zeros((len(uv), 4), np.float32)
    kernels(SOURCE, ALL_TEXTURES)("lookup_texture", len(uv), tables.textures, tables.texels,
                                  tables.bindings[0]["texture"], np.ascontiguousarray(uv, np.float32), out)
    return out[:, :3]


def wrap(i, n, mode):
    if mode == "clamp":
        return np.clip(i, 0, n - 1)
    if mode == "mirror":
        m = np.mod(i, 2 * n)
        return np.where(m < n, m, 2 * n - 1 - m)
    return np.mod(i, n)


def reference_lookup(rgb, uv, mode, filt, to_uv):
    """The bitmap's definition (kernels/textures/bitmap.cl) in NumPy, float64."""
    h, w, _ = rgb.shape
    st = np.column_stack([uv, np.ones(len(uv))]) @ to_uv.T
    x, y = st[:, 0] * w, st[:, 1] * h
    if filt == "nearest":
        return rgb[wrap(np.floor(y).astype(int), h, mode), wrap(np.floor(x).astype(int), w, mode)]
    x, y = x - 0.5, y - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    ax, ay = (x - x0)[:, None], (y - y0)[:, None]

    def texel(i, j):
        return rgb[wrap(j, h, mode), wrap(i, w, mode)]
    top = (1 - ax) * texel(x0, y0) + ax * texel(x0 + 1, y0)
    bottom = (1 - ax) * texel(x0, y0 + 1) + ax * texel(x0 + 1, y0 + 1)
    return (1 - ay) * top + ay * bottom


FORMATS = {   # name: (texels, linear), and the tolerance of the stored precision
    "srgb8": (lambda r: r.integers(0, 256, (5, 7, 3)).astype(np.uint8), False, 1e-5),
    "linear8": (lambda r: r.integers(0, 256, (5, 7, 3)).astype(np.uint8), True, 1e-5),
    "grey8": (lambda r: r.integers(0, 256, (5, 7, 1)).astype(np.uint8), False, 1e-5),
    "rgba8": (lambda r: r.integers(0, 256, (5, 7, 4)).astype(np.uint8), False, 1e-5),
    "half": (lambda r: r.uniform(0, 50, (5, 7, 3)).astype(np.float32), True, 2e-3),
    "float": (lambda r: r.uniform(0, 1e6, (5, 7, 3)).astype(np.float32), True, 1e-5),
}


@pytest.mark.parametrize("filt", ["nearest", "bilinear"])
@pytest.mark.parametrize("mode", ["repeat", "mirror", "clamp"])
@pytest.mark.parametrize("fmt", list(FORMATS))
def test_bitmap_lookup_matches_its_definition(kernels, fmt, mode, filt):
    """At random uv (a seed of the case's own: Python's hash of strings changes between runs), but
    for nearest lookups none within 1e-4 texels of a texel's edge, where the kernel's float32 and
    the reference's float64 may round to either neighbour."""
    rng = np.random.default_rng(zlib.crc32(f"{fmt} {mode} {filt}".encode()))
    make, linear, tolerance = FORMATS[fmt]
    image = Image(make(rng), linear)
    to_uv = np.array([[1.7, 0.3, -0.4], [-0.2, 1.3, 0.25], [0, 0, 1]])
    tex = texture("bitmap", image=image, wrap=mode, filter=filt, to_uv=to_uv)
    uv = rng.uniform(-1.5, 2.5, (500, 2)).astype(np.float32).astype(np.float64)   # as the kernel gets them
    if filt == "nearest":
        h, w = image.rgb().shape[:2]
        st = np.column_stack([uv, np.ones(len(uv))]) @ to_uv.T * (w, h, 1)
        edge = np.abs(st[:, :2] - np.round(st[:, :2])).min(axis=1)
        uv = uv[edge > 1e-4]
        assert len(uv) > 450
    expected = reference_lookup(image.rgb(), uv, mode, filt, to_uv)
    got = lookup(kernels, tex, uv)
    np.testing.assert_allclose(got, expected, rtol=tolerance, atol=tolerance * np.max(expected))


@pytest.mark.parametrize("mode", ["repeat", "mirror", "clamp"])
def test_coordinates_beyond_any_image_look_up_a_texel(kernels, mode):
    """NaN, infinite and huge uvs (a degenerate transform, a broken file) read a texel of the
    image, never memory beyond it."""
    texels = np.arange(1, 13, dtype=np.uint8).reshape(3, 4, 1) * 20
    tex = texture("bitmap", image=Image(texels, linear=True), wrap=mode, filter="bilinear")
    uv = np.array([[np.nan, 0.5], [np.inf, -np.inf], [1e30, -1e30], [3e9, 0.25], [-0.0, np.nan]])
    got = lookup(kernels, tex, uv)
    assert np.all(np.isfinite(got)) and np.all(got >= 20 / 255 - 1e-6) and np.all(got <= 240 / 255 + 1e-6)


def test_srgb_decoding_is_the_standards_curve(kernels):
    """Each 8-bit value decodes to the IEC 61966-2-1 curve, whose two pieces meet at 0.04045."""
    values = np.arange(256, dtype=np.uint8).reshape(1, 256, 1)
    tex = texture("bitmap", image=Image(values), filter="nearest")
    uv = np.column_stack([(np.arange(256) + 0.5) / 256, np.full(256, 0.5)])
    got = lookup(kernels, tex, uv)[:, 0]
    c = np.arange(256) / 255
    exact = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    np.testing.assert_allclose(got, exact, rtol=1e-6, atol=1e-9)
    assert srgb_to_linear(0.5) == pytest.approx(0.214041, abs=1e-6)


def test_checkerboard_scale_and_mix(kernels):
    rng = np.random.default_rng(3)
    uv = rng.uniform(-2, 2, (400, 2))
    board = texture("checkerboard", color0=[0.9, 0.1, 0.2], color1=0.3, to_uv=np.diag([4.0, 2.0, 1.0]))
    st = uv * [4, 2]
    same = ((st[:, 0] - np.floor(st[:, 0])) > 0.5) == ((st[:, 1] - np.floor(st[:, 1])) > 0.5)
    np.testing.assert_allclose(lookup(kernels, board, uv), np.where(same[:, None], [0.9, 0.1, 0.2], 0.3), rtol=1e-6)
    image = Image(rng.integers(0, 256, (4, 4, 3)).astype(np.uint8))
    bitmap = texture("bitmap", image=image)
    plain = reference_lookup(image.rgb(), uv, "repeat", "bilinear", np.eye(3))
    np.testing.assert_allclose(lookup(kernels, texture("scale", tex=bitmap, scale=[2, 0.5, 1]), uv),
                               plain * [2, 0.5, 1], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(lookup(kernels, texture("mix", tex1=0.2, tex2=bitmap, amount=0.25), uv),
                               0.75 * 0.2 + 0.25 * plain, rtol=1e-5, atol=1e-6)
    # an amount beyond [0, 1] extrapolates, as pbrt-v4's MixTexture does, within the host's bounds
    beyond = texture("mix", tex1=0.2, tex2=bitmap, amount=-0.5)
    values = lookup(kernels, beyond, uv)
    np.testing.assert_allclose(values, 1.5 * 0.2 - 0.5 * plain, rtol=1e-5, atol=1e-6)
    low, high = beyond.kind.bounds(beyond)
    assert np.all(values >= low - 1e-6) and np.all(values <= high + 1e-6)


def test_clamp_clamps_after_the_filtering_as_pbrt_v4s_materials(kernels):
    """clamp(bilinear(2 x texels)), not the bilinear blend of clamped texels: between a texel of
    0.3 and one of 0.9 (0.6 and 1.8 scaled) the value reaches 1 a third of the way from the first,
    where the blend of clamped texels would be 0.73. pbrt-v4 clamps the value it looks up
    (DiffuseMaterial::GetBxDF; SpectrumImageTexture::Evaluate)."""
    rng = np.random.default_rng(5)
    uv = rng.uniform(-2, 2, (400, 2))
    image = Image(rng.integers(0, 256, (4, 4, 3)).astype(np.uint8))
    scaled = texture("scale", tex=texture("bitmap", image=image), scale=2.0)
    plain = reference_lookup(image.rgb(), uv, "repeat", "bilinear", np.eye(3)) * 2
    clamped = lookup(kernels, texture("clamp", tex=scaled), uv)
    np.testing.assert_allclose(clamped, np.clip(plain, 0, 1), rtol=1e-5, atol=1e-6)
    assert np.any((plain > 1).any(1) & (plain < 1).any(1))      # points where channels straddle
    for bounds in ({"low": 0.5, "high": 0.2}, {"high": texture("checkerboard")}):
        with pytest.raises(ValueError, match="low must not exceed high|high must be a number or three numbers"):
            texture("clamp", tex=scaled, **bounds)


def checker(st):
    """The checkerboard's square index (kernels/textures/checkerboard.cl): 0 or 1 at st."""
    f = st - np.floor(st)
    return ((f[:, 0] > 0.5) != (f[:, 1] > 0.5)).astype(int)


def test_textures_nest_to_any_depth(kernels):
    """pbrt-v4 nests textures freely: a mix of a checkerboard and a colour, a checkerboard of
    checkerboards of images, a mix whose three inputs combine others, and chains thousands long,
    each against the same definitions in NumPy."""
    rng = np.random.default_rng(3)
    uv = rng.uniform(-2, 2, (257, 2))
    image = Image(rng.integers(0, 256, (4, 4, 3)).astype(np.uint8))
    bitmap = texture("bitmap", image=image)
    plain = reference_lookup(image.rgb(), uv, "repeat", "bilinear", np.eye(3))
    scaled = np.diag([4.0, 4.0, 1.0])
    board = texture("checkerboard", color0=[0.8, 0.8, 0.8], color1=[0.1, 0.1, 0.1], to_uv=scaled)
    board_ref = np.where(checker(uv * 4)[:, None] == 0, 0.8, 0.1)
    np.testing.assert_allclose(lookup(kernels, texture("mix", tex1=board, tex2=[0.2, 0.5, 0.2], amount=0.3), uv),
                               0.7 * board_ref + 0.3 * np.array([0.2, 0.5, 0.2]), rtol=1e-5, atol=1e-6)
    boards = texture("checkerboard", color0=board, color1=texture("checkerboard", color0=bitmap, color1=0.5))
    expected = np.where(checker(uv)[:, None] == 0, board_ref, np.where(checker(uv)[:, None] == 0, plain, 0.5))
    np.testing.assert_allclose(lookup(kernels, boards, uv), expected, rtol=1e-5, atol=1e-6)
    three = texture("mix", tex1=boards, tex2=texture("scale", tex=bitmap, scale=2.0),
                    amount=texture("mix", tex1=board, tex2=0.0, amount=0.5))
    a = (0.5 * board_ref)[:, :1]
    np.testing.assert_allclose(lookup(kernels, three, uv), (1 - a) * expected + a * 2 * plain, rtol=1e-5, atol=1e-6)
    for length in (3, 3000):
        chain = bitmap
        for k in range(length):
            chain = texture("scale", tex=chain, scale=1.0001) if k % 2 else texture("mix", tex1=0.0, tex2=chain, amount=1.0)
        np.testing.assert_allclose(lookup(kernels, chain, uv), plain * 1.0001 ** (length // 2), rtol=1e-4, atol=1e-6)
        assert chain.mean() == pytest.approx(image.rgb().reshape(-1, 3).mean(0) * 1.0001 ** (length // 2))


def test_a_tree_beyond_the_kernels_registers_is_refused():
    """A balanced tree of scales of 2^8 leaves needs 9 registers (Sethi-Ullman), one more than
    the kernels have; of 2^7, 8."""
    def tree(levels):
        if levels == 0:
            return texture("checkerboard")
        return texture("scale", tex=tree(levels - 1), scale=tree(levels - 1))
    compile_textures([[("", 0, 3, tree(7))]])
    with pytest.raises(ValueError, match="needs 9 registers"):
        compile_textures([[("", 0, 3, tree(8))]])


def test_a_material_reads_its_textured_parameters_at_the_hit(kernels):
    """A colour texture fills its slot's rgb; a number parameter (roughconductor's alpha) takes the
    texture's luminance; the row holds their means for the host's constants."""
    rng = np.random.default_rng(5)
    colours = Image(rng.integers(0, 256, (3, 3, 3)).astype(np.uint8))
    grey = Image(rng.integers(10, 256, (2, 2, 3)).astype(np.uint8), linear=True)
    table = MaterialTable()
    row = table.add(Material("roughconductor", {"specular_reflectance": texture("bitmap", image=colours),
                                                "alpha": texture("bitmap", image=grey, filter="nearest"),
                                                "eta": 0.2, "k": 3.0}))
    tables = compile_textures(table.textures)
    materials = table.rows.copy()
    materials["textures"] = tables.first
    uv = rng.uniform(0, 1, (64, 2))
    out = np.zeros(len(uv), MATERIAL)
    kernels(SOURCE, ALL_TEXTURES)("shade", len(uv), materials, tables.bindings, tables.textures, tables.texels,
                                  np.ascontiguousarray(uv, np.float32), out)
    np.testing.assert_allclose(out["p2"][:, :3], reference_lookup(colours.rgb(), uv, "repeat", "bilinear", np.eye(3)),
                               rtol=1e-5, atol=1e-6)
    alpha = reference_lookup(grey.rgb(), uv, "repeat", "nearest", np.eye(3)) @ [0.212671, 0.715160, 0.072169]
    np.testing.assert_allclose(out["p0"][:, 3], alpha, rtol=1e-5)
    np.testing.assert_allclose(out["p0"][:, :3], 0.2)           # untextured slots as they were
    assert table.rows[row]["p0"][3] == pytest.approx(grey.rgb().reshape(-1, 3).mean(0) @ [0.212671, 0.715160, 0.072169], rel=1e-5)
    again = table.get(row)
    assert again.params["alpha"] is table.textures[row][1][3]   # the viewer's editor sees the textures


def test_a_scene_without_textures_compiles_no_texture_code():
    from pathtrace.compiler.compiled import CompiledScene
    from pathtrace.device.opencl import kernel_source
    from pathtrace.scene import load_scene
    scene = load_scene("simple")
    features = CompiledScene(scene).features(scene.settings, scene.camera)
    assert features.textures == () and "TEXTURES" not in features.defines()
    assert "eval_texture" not in kernel_source(features=features)


# -- texture coordinates from files ---------------------------------------------------------

def ply_with(tmp_path, names):
    from plyfile import PlyData, PlyElement
    v = np.zeros(3, [("x", "f4"), ("y", "f4"), ("z", "f4"), (names[0], "f4"), (names[1], "f4")])
    v["x"], v["y"] = [0, 1, 0], [0, 0, 1]
    v[names[0]], v[names[1]] = [0.1, 0.2, 0.3], [0.7, 0.8, 0.9]
    f = np.array([([0, 1, 2],)], [("vertex_indices", "i4", (3,))])
    path = tmp_path / "t.ply"
    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]).write(str(path))
    return path


@pytest.mark.parametrize("names", [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")])
def test_ply_texture_coordinates_are_read_as_they_are(tmp_path, names):
    uvs = read_mesh(ply_with(tmp_path, names), "test").uvs
    np.testing.assert_allclose(uvs, [[0.1, 0.7], [0.2, 0.8], [0.3, 0.9]], rtol=1e-6)


def test_obj_and_gltf_texture_coordinates_put_v_0_at_the_images_top(tmp_path):
    """OBJ's vt has v = 0 at an image's bottom: flipped, as Mitsuba 3's OBJ reader does. glTF's
    TEXCOORD_0 has it at the top already (trimesh flips it on reading and writing)."""
    import trimesh
    (tmp_path / "q.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\nf 1/1 2/2 3/3\n")
    np.testing.assert_allclose(read_mesh(tmp_path / "q.obj", "test").uvs, [[0.1, 0.8], [0.3, 0.6], [0.5, 0.4]], rtol=1e-6)
    mesh = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False,
                           visual=trimesh.visual.TextureVisuals(uv=[[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]]))
    mesh.export(tmp_path / "q.glb")
    np.testing.assert_allclose(read_mesh(tmp_path / "q.glb", "test").uvs, [[0.1, 0.8], [0.3, 0.6], [0.5, 0.4]], rtol=1e-6)


def test_texture_coordinates_that_are_not_finite_are_refused(tmp_path):
    path = ply_with(tmp_path, ("u", "v"))
    data = path.read_bytes().replace(np.float32(0.8).tobytes(), np.float32(np.nan).tobytes())
    path.write_bytes(data)
    with pytest.raises(UserError, match=r"t.ply: the texture coordinates of vertex 1 are not finite"):
        read_mesh(path, "test")


# -- bad texture files, in scene files --------------------------------------------------------

def bitmap_scene(tmp_path, filename, extra=""):
    return write(tmp_path, f'<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
                           f'<string name="filename" value="{filename}"/>{extra}</texture></bsdf></shape>')


def make_bad(tmp_path, case):
    if case == "truncated":
        PILImage.fromarray(np.zeros((64, 64, 3), np.uint8) + 100).save(tmp_path / "t.png")
        data = (tmp_path / "t.png").read_bytes()
        (tmp_path / "t.png").write_bytes(data[:len(data) // 2])
        return "t.png", "", "is not a readable PNG image"
    if case == "not an image":
        (tmp_path / "t.png").write_text("hello")
        return "t.png", "", "is not a readable PNG image"
    if case == "huge":
        PILImage.fromarray(np.zeros((1, 16385), np.uint8)).save(tmp_path / "t.png")
        return "t.png", "", "is 16385x1 texels; pathtrace takes at most 16384 on a side"
    if case == "NaN texels":
        (tmp_path / "t.pfm").write_bytes(b"PF\n2 1\n-1.0\n" + np.array([1, 2, np.nan, 1, 1, 1], "<f4").tobytes())
        return "t.pfm", "", "holds negative, NaN or infinite pixels"
    if case == "unknown format":
        (tmp_path / "t.gif").write_bytes(b"GIF89a")
        return "t.gif", "", "unknown image format '.gif'"
    if case == "unknown wrap mode":
        PILImage.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / "t.png")
        return "t.png", '<string name="wrap_mode" value="wobble"/>', "wrap: unknown wrap 'wobble' (known: repeat, mirror, clamp)"
    raise AssertionError(case)


@pytest.mark.parametrize("case", ["truncated", "not an image", "huge", "NaN texels", "unknown format", "unknown wrap mode"])
def test_bad_texture_files_fail_with_one_line(tmp_path, case):
    filename, extra, message = make_bad(tmp_path, case)
    with pytest.raises(UserError) as e:
        read_mitsuba_file(bitmap_scene(tmp_path, filename, extra))
    assert message in str(e.value) and "scene.xml:3" in str(e.value) and "\n" not in str(e.value), str(e.value)


def test_image_formats_read_alike(tmp_path):
    """PNG, TGA and BMP hold the same 8-bit texels; a 16-bit PNG decodes to float."""
    rng = np.random.default_rng(1)
    rgb = rng.integers(0, 256, (3, 5, 3)).astype(np.uint8)
    for suffix in ("png", "tga", "bmp"):
        PILImage.fromarray(rgb).save(tmp_path / f"t.{suffix}")
        image = read_image(tmp_path / f"t.{suffix}", "test")
        assert image.texels.dtype == np.uint8 and not image.linear
        np.testing.assert_array_equal(image.texels, rgb)
    grey16 = (rng.integers(0, 65536, (3, 5))).astype(np.uint16)
    PILImage.fromarray(grey16).save(tmp_path / "g.png")
    image = read_image(tmp_path / "g.png", "test")
    np.testing.assert_allclose(image.texels[..., 0], srgb_to_linear(grey16 / 65535.0), rtol=1e-6, atol=1e-7)


def test_a_shared_texture_is_stored_once(tmp_path):
    PILImage.fromarray(np.zeros((8, 8, 3), np.uint8)).save(tmp_path / "t.png")
    body = ('<texture type="bitmap" id="t"><string name="filename" value="t.png"/></texture>'
            '<shape type="sphere"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>'
            '<shape type="sphere"><point name="center" x="3" y="0" z="0"/><bsdf type="plastic">'
            '<ref name="diffuse_reflectance" id="t"/></bsdf></shape>' + SPHERE)
    scene = read_mitsuba_file(write(tmp_path, body))
    assert len(scene.materials.all_textures()) == 1
    tables = compile_textures(scene.materials.textures)
    assert len(tables.texels) == 1024 + 8 * 8 * 4      # the sRGB table, then the image once (rgb as rgba)


# -- alpha masks ------------------------------------------------------------------------------

def masked_wall_scene(opacity, nee):
    """A black wall of the given opacity filling the view in front of a white sky: each pixel
    sees the sky through it with probability 1 - opacity."""
    from pathtrace.api import load_dict
    return load_dict({
        "camera": {"eye": [0, 0, 3], "look_at": [0, 0, 0], "vfov": 30},
        "environment": {"color": 1.0},
        "render": {"width": 16, "height": 16, "max_depth": 4, "nee": nee},
        "textures": {"holes": {"type": "checkerboard", "color0": 0.0, "color1": 1.0, "uv_scale": 64}},
        "materials": {"wall": {"type": "diffuse", "rho_d": 0.0, "opacity": opacity}},
        "meshes": [{"material": "wall", "vertices": [[-9, -9, 0], [9, -9, 0], [9, 9, 0], [-9, 9, 0]],
                    "faces": [[0, 1, 2, 3]], "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]]}]})


@pytest.mark.parametrize("nee", [False, True], ids=["no-nee", "nee"])
@pytest.mark.parametrize("opacity", [0.3, "holes"])
def test_a_masked_surface_lets_through_one_minus_its_opacity(backend, opacity, nee):
    """The pixels' mean is the sky times 1 - opacity: 0.7 for a constant 0.3, and 0.5 for a fine
    checkerboard of opaque and clear squares; a Binomial count, so the tolerance is its standard
    error."""
    from pathtrace.rendering.renderer import Renderer
    r = Renderer(backend, masked_wall_scene(opacity, nee))
    r.add_samples(64)
    expected = 0.7 if opacity == 0.3 else 0.5
    mean, n = float(r.mean().mean()), 16 * 16 * 64
    assert abs(mean - expected) < 5 * np.sqrt(expected * (1 - expected) / n), mean


def test_opacity_is_checked_and_written_back(tmp_path):
    from pathtrace.api import load_dict
    from pathtrace.scene.toml_reader import read_scene_file
    from pathtrace.scene.toml_writer import scene_toml
    base = {"spheres": [{"center": [0, 0, 0], "radius": 1, "material": "m"}]}
    with pytest.raises(UserError, match=r"materials.m.opacity: must be at most 1.0, got 1.5"):
        load_dict({**base, "materials": {"m": {"type": "diffuse", "rho_d": 0.5, "opacity": 1.5}}})
    PILImage.fromarray(np.full((2, 2), 128, np.uint8)).save(tmp_path / "a.png")
    scene = load_dict({**base, "textures": {"a": {"type": "bitmap", "file": "a.png", "raw": True}},
                       "materials": {"m": {"type": "diffuse", "rho_d": 0.5, "opacity": "a"}}}, folder=tmp_path)
    (tmp_path / "out.toml").write_text(scene_toml(scene, tmp_path / "out.toml"))
    again = read_scene_file(tmp_path / "out.toml")
    opacity = again.materials.get(0).opacity
    assert isinstance(opacity, Texture) and opacity.mean() == pytest.approx(128 / 255)


# -- normal and bump maps ---------------------------------------------------------------------

GRADIENT_SOURCE = """
kernel void gradient(const global Texture *textures, const global uchar *texels,
                     const global float2 *uv, global float2 *out)
{
    SceneData sc;
    sc.textures = textures;
    sc.texels = texels;
    int i = get_global_id(0);
    out[i] = grad_bitmap(&sc, &textures[0], uv[i]);
}
"""


@pytest.mark.parametrize("mode", ["repeat", "mirror", "clamp"])
def test_bitmap_gradient_is_the_slope_of_its_bilinear_lookup(kernels, mode):
    """grad_bitmap (a bump map's slopes) against central differences of the NumPy lookup, at
    points away from texel-centre lines, where the bilinear interpolant is smooth."""
    rng = np.random.default_rng(11)
    image = Image(rng.integers(0, 256, (6, 5, 3)).astype(np.uint8), linear=True)
    to_uv = np.array([[1.3, 0.4, 0.1], [-0.3, 0.9, 0.2], [0, 0, 1]])
    tex = texture("bitmap", image=image, wrap=mode, to_uv=to_uv)
    tables = compile_textures([[("", 24, 1, tex)]])
    uv = rng.uniform(0.05, 0.95, (300, 2))
    out = np.zeros((len(uv), 2), np.float32)
    kernels(GRADIENT_SOURCE, Features(textures=("bitmap",)))("gradient", len(uv), tables.textures, tables.texels,
                                                              np.ascontiguousarray(uv, np.float32), out)
    lum = np.array([0.212671, 0.715160, 0.072169])
    f = lambda q: reference_lookup(image.rgb(), q, mode, "bilinear", to_uv) @ lum  # noqa: E731
    h = 1e-5
    numeric = np.column_stack([(f(uv + [h, 0]) - f(uv - [h, 0])) / (2 * h), (f(uv + [0, h]) - f(uv - [0, h])) / (2 * h)])
    # the interpolant kinks on the lines through texel centres and at the image's border (where
    # the wrap modes differ): central differences across those are left out
    st = (np.column_stack([uv, np.ones(len(uv))]) @ to_uv.T)[:, :2] * [5, 6]
    smooth = np.all((np.abs((st - 0.5) % 1 - 0.5) < 0.49) & (st > 0.6) & (st < [4.4, 5.4]), axis=1)
    assert smooth.sum() > 50
    np.testing.assert_allclose(out[smooth], numeric[smooth], rtol=1e-3, atol=1e-3 * np.abs(numeric).max())


def flat_map_scene(kind, tmp_path):
    """The material-spheres floor scene with a map that perturbs nothing: a normal map of
    (0, 0, 1) everywhere, or a bump map of constant height."""
    from pathtrace.api import load_dict
    value = [128, 128, 255] if kind == "normal_map" else [77, 77, 77]
    PILImage.fromarray(np.full((4, 4, 3), value, np.uint8)).save(tmp_path / "flat.png")
    material = {"type": "diffuse", "rho_d": 0.6}
    if kind:
        material[kind] = {"type": "bitmap", "file": "flat.png", "raw": True}
    return load_dict({
        "camera": {"eye": [0, 2, 4], "look_at": [0, 0.3, 0], "vfov": 40},
        "environment": {"color": 0.3}, "render": {"width": 24, "height": 16},
        "materials": {"m": material, "lamp": {"type": "emitter", "Le": 30}},
        "spheres": [{"center": [0, 0.5, 0], "radius": 0.5, "material": "m"},
                    {"center": [2, 3, 1], "radius": 0.3, "material": "lamp"}],
        "meshes": [{"material": "m", "vertices": [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]],
                    "faces": [[0, 1, 2, 3]], "uvs": [[0, 0], [0, 1], [1, 1], [1, 0]]}]}, folder=tmp_path)


@pytest.mark.parametrize("kind", ["normal_map", "bump_map"])
def test_a_map_that_perturbs_nothing_changes_nothing(backend, tmp_path, kind):
    """The 8-bit (0, 0, 1) normal is (128, 128, 255): within 1/255 of the geometric normal, so
    the image moves by less than a percent; a constant height has no slopes: the same image."""
    from pathtrace.rendering.renderer import Renderer
    images = []
    for k in (None, kind):
        r = Renderer(backend, flat_map_scene(k, tmp_path))
        r.add_samples(16)
        images.append(r.mean())
    if kind == "bump_map":
        np.testing.assert_allclose(images[1], images[0], rtol=1e-5, atol=1e-6)
    else:
        assert abs(images[1].mean() / images[0].mean() - 1) < 0.01


def test_a_bump_map_and_the_normal_map_of_its_normal_render_alike(backend, tmp_path):
    """A height ramp along u tilts the floor's normal by a constant angle; a normal map of that
    normal (float texels, no rounding) perturbs it the same. Mitsuba 3.9 treats both alike (its
    PerturbedBSDF: Schuessler's flip and the shadowing term of the tilt); pathtrace's bump map
    lacked both, and lit this floor under a grazing lamp brighter (review 2026-11-28, F9)."""
    from pathtrace.api import load_dict
    from pathtrace.io.images import write_image
    from pathtrace.rendering.renderer import Renderer
    width, step, scale = 64, 2, 20.0
    ramp = np.tile((np.arange(width) * step).astype(np.uint8)[None, :, None], (4, 1, 3))
    PILImage.fromarray(ramp).save(tmp_path / "ramp.png")
    # the floor's dp/du is (6, 0, 0), dp/dv (0, 0, 6): the bumped normal is (-s, 6, 0), s the
    # height's slope along u, in the frame (dp/du, n x dp/du, n) = (x, -z, y) that is (-s, 0, 6)
    s = step / 255 * width * scale
    m = np.array([-s, 0.0, 6.0]) / np.hypot(s, 6.0)
    write_image(tmp_path / "normal.exr", np.tile((m + 1) / 2, (4, 4, 1)).astype(np.float32))
    images = []
    for maps in ({"bump_map": {"type": "bitmap", "file": "ramp.png", "raw": True, "wrap": "clamp"}, "bump_scale": scale},
                 {"normal_map": {"type": "bitmap", "file": "normal.exr", "raw": True}}):
        scene = load_dict({
            "camera": {"eye": [0, 3, 2], "look_at": [0, 0, 0], "vfov": 30},
            "environment": {"color": 0.1}, "render": {"width": 16, "height": 12, "max_depth": 2},
            "materials": {"m": {"type": "diffuse", "rho_d": 0.6, **maps}, "lamp": {"type": "emitter", "Le": 50}},
            "spheres": [{"center": [4, 0.6, 0], "radius": 0.3, "material": "lamp"}],
            "meshes": [{"material": "m", "vertices": [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]],
                        "faces": [[0, 1, 2, 3]], "uvs": [[0, 0], [0, 1], [1, 1], [1, 0]]}]}, folder=tmp_path)
        r = Renderer(backend, scene)
        r.add_samples(64)
        images.append(r.mean())
    np.testing.assert_allclose(images[0], images[1], rtol=2e-3, atol=1e-5)


@pytest.mark.specialised
@pytest.mark.parametrize("integrator", ["path", "bdpt"])
def test_a_constant_normal_map_builds_the_scenes_own_program(backend, tmp_path, integrator):
    """A normal map may be any texture; kernels/normal_maps.cl reads a bump map's slopes from a
    bitmap, so a scene whose only normal map is a constant still compiles the bitmap's kernel
    (its own program failed to build: grad_bitmap undeclared). The constant tilts the floor's
    normal as the same normal in a bitmap does."""
    from pathtrace.api import load_dict
    from pathtrace.io.images import write_image
    from pathtrace.rendering.renderer import Renderer
    write_image(tmp_path / "normal.exr", np.full((2, 2, 3), [0.6, 0.5, 0.9], np.float32))
    images = []
    for normal_map in ({"type": "constant", "value": [0.6, 0.5, 0.9]}, {"type": "bitmap", "file": "normal.exr", "raw": True}):
        scene = load_dict({
            "camera": {"eye": [0, 3, 2], "look_at": [0, 0, 0], "vfov": 30},
            "render": {"width": 12, "height": 8, "max_depth": 3, "integrator": integrator},
            "materials": {"m": {"type": "diffuse", "rho_d": 0.6, "normal_map": normal_map},
                          "lamp": {"type": "emitter", "Le": 20}},
            "spheres": [{"center": [2, 1, 0], "radius": 0.3, "material": "lamp"}],
            "meshes": [{"material": "m", "vertices": [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]],
                        "faces": [[0, 1, 2, 3]], "uvs": [[0, 0], [0, 1], [1, 1], [1, 0]]}]}, folder=tmp_path)
        r = Renderer(backend, scene)
        assert not r.uses_generic_program
        r.add_samples(64)
        images.append(r.mean())
    np.testing.assert_allclose(images[0].mean(), images[1].mean(), rtol=0.03)


def test_a_map_around_a_map_keeps_the_inner_one(tmp_path, capsys):
    PILImage.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / "m.png")
    bitmap = '<texture type="bitmap" name="normalmap"><string name="filename" value="m.png"/></texture>'
    scene = read_mitsuba_file(write(tmp_path, f'<shape type="sphere"><bsdf type="bumpmap">{bitmap}'
                                              f'<bsdf type="normalmap">{bitmap}<bsdf type="diffuse"/></bsdf></bsdf></shape>'))
    m = scene.materials.get(0)
    assert m.normal_map is not None and m.bump_map is None
    assert "a bumpmap around another map; pathtrace applies the inner one only" in capsys.readouterr().err


def test_shading_maps_in_scene_files(tmp_path):
    from pathtrace.api import load_dict
    PILImage.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / "m.png")
    base = {"spheres": [{"center": [0, 0, 0], "radius": 1, "material": "m"}]}
    bitmap = {"type": "bitmap", "file": "m.png", "raw": True}
    scene = load_dict({**base, "materials": {"m": {"type": "diffuse", "rho_d": 0.5, "bump_map": bitmap,
                                                   "bump_scale": 0.1}}}, folder=tmp_path)
    bump = scene.materials.get(0).bump_map
    assert bump.type == "scale" and bump.params["scale"][0] == pytest.approx(0.1)
    assert scene.materials.get(0).perturbation == "mitsuba"
    pbrt_like = {"type": "diffuse", "rho_d": 0.5, "normal_map": bitmap, "perturbation": "pbrt"}
    scene = load_dict({**base, "materials": {"m": pbrt_like}}, folder=tmp_path)
    assert scene.materials.get(0).perturbation == "pbrt"
    assert scene.materials.rows[0]["flags"] & PBRT_PERTURBATION
    for material, message in [({"normal_map": bitmap, "bump_map": bitmap}, "give a normal_map or a bump_map, not both"),
                               ({"bump_scale": 2}, "materials.m.bump_scale: scales a bump_map, and there is none"),
                               ({"perturbation": "pbrt"}, "materials.m.perturbation: says how a normal_map or bump_map "
                                                          "perturbs, and there is none"),
                               ({"bump_map": bitmap, "perturbation": "pbtr"},
                                "materials.m.perturbation: must be 'mitsuba' or 'pbrt', got 'pbtr'; did you mean 'pbrt'"),
                               ({"bump_map": bitmap, "perturbation": 1}, "must be 'mitsuba' or 'pbrt', got 1$"),
                               ({"bump_map": {"type": "checkerboard"}}, "must be a bitmap texture")]:
        with pytest.raises(UserError, match=message):
            load_dict({**base, "materials": {"m": {"type": "diffuse", "rho_d": 0.5, **material}}}, folder=tmp_path)
    # their defaults stated without a map are as good as left out
    stated = load_dict({**base, "materials": {"m": {"type": "diffuse", "rho_d": 0.5, "bump_scale": 1,
                                                    "perturbation": "mitsuba"}}}, folder=tmp_path)
    plain = load_dict({**base, "materials": {"m": {"type": "diffuse", "rho_d": 0.5}}}, folder=tmp_path)
    assert stated.materials.rows.tobytes() == plain.materials.rows.tobytes()


# -- the command line and the viewer ----------------------------------------------------------

@pytest.mark.parametrize("textures,message", [
    ('a = { type = "checkerboard", color0 = "b" }\nb = { type = "checkerboard", color0 = "a" }',
     "textures.b.color0: a texture reference cycle: 'a -> b -> a'"),
    ('a = { type = "bitmap", file = "nowhere.png" }', "nowhere.png' does not exist"),
    ('a = { type = "bitmap", file = "t.png", wrap = "wobble" }', "textures.a.wrap: must be one of repeat, mirror, clamp"),
    ('a = { type = "bitmap", file = "t.png", uv_scale = [1, "x"] }', "textures.a.uv_scale: must be a number or a list of 2"),
    ('a = { type = "bitmap", file = "x\\u0000y.png" }', "x\\x00y.png': a file name cannot hold a NUL byte"),
])
def test_a_bad_texture_is_one_line_and_writes_nothing(tmp_path, textures, message):
    from tests.test_cli import pathtrace
    PILImage.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / "t.png")
    scene = tmp_path / "s.toml"
    scene.write_text(f'[textures]\n{textures}\n\n[materials]\nm = {{ type = "diffuse", rho_d = "a" }}\n\n'
                     '[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = "m"\n')
    out = tmp_path / "o.png"
    r = pathtrace("render", scene, "-o", out, "--spp", "1", "--size", "8x8")
    assert r.returncode == 1 and message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not out.exists()


def test_the_panel_names_a_pickeds_textures():
    from pathtrace.viewer.panel import texture_label
    image = Image(np.zeros((2, 2, 3), np.uint8), path="/some/where/wood.png")
    assert texture_label(Texture("bitmap", {"image": image}, "wood")) == "texture 'wood' (bitmap wood.png)"
    assert texture_label(texture("checkerboard")) == "texture (checkerboard)"


def test_a_bump_map_of_a_combining_texture_is_refused_in_one_line_even_when_scaled(tmp_path):
    """A checkerboard as a bump map with a bump_scale raised ValueError from the scale texture
    (inputs nest one level deep) before the bump map's own check (found by the scene fuzzer)."""
    from pathtrace.errors import UserError
    from pathtrace.scene import load_scene
    (tmp_path / "s.toml").write_text('[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = { type = "conductor", '
                                     'bump_map = { type = "checkerboard" }, bump_scale = 0.5 }\n')
    with pytest.raises(UserError, match="bump_map: a bump map must be a bitmap"):
        load_scene(str(tmp_path / "s.toml"))
    (tmp_path / "s.xml").write_text('<scene version="3.0.0"><shape type="sphere"><bsdf type="bumpmap">'
                                    '<texture type="checkerboard"/><float name="scale" value="2"/>'
                                    '<bsdf type="diffuse"/></bsdf></shape></scene>')
    with pytest.raises(UserError, match="a bump map must be a bitmap"):
        load_scene(str(tmp_path / "s.xml"))


@pytest.mark.parametrize("dtype,channels,linear", [(np.uint8, 3, False), (np.uint8, 4, False), (np.uint8, 1, True),
                                                   (np.float32, 3, True), (np.float32, 1, True)])
def test_an_images_summary_is_its_decoded_texels_mean_and_extremes(dtype, channels, linear):
    """The materials' host side reads a texture's mean, least and greatest rgb through
    Image.summary, which for 8-bit images takes histograms instead of decoding every texel."""
    rng = np.random.default_rng(channels)
    texels = rng.integers(3, 250, (37, 53, channels)) if dtype == np.uint8 else rng.uniform(0, 40, (37, 53, channels))
    image = Image(texels.astype(dtype), linear)
    rgb = image.rgb().reshape(-1, 3)
    mean, low, high = image.summary
    np.testing.assert_allclose(mean, rgb.mean(axis=0), rtol=1e-12)
    np.testing.assert_array_equal(low, rgb.min(axis=0))
    np.testing.assert_array_equal(high, rgb.max(axis=0))


def test_an_image_file_that_is_a_folder_or_has_no_suffix_is_one_line(tmp_path):
    """A folder named as a texture's file was refused as "unknown image format ''"."""
    from pathtrace.textures.bitmap import read_image
    (tmp_path / "maps").mkdir()
    (tmp_path / "plain").write_bytes(b"x")
    with pytest.raises(UserError, match=r"^t: texture '.*maps' is not a regular file$"):
        read_image(tmp_path / "maps", "t")
    with pytest.raises(UserError, match=r"^t: '.*plain': an image file's name needs its format's suffix \(.png"):
        read_image(tmp_path / "plain", "t")
