"""Every registered analytic shape kind (app/shapes/registry.py), through its examples: the BVH
finds its nearest hits as brute force does, its area sampling's density integrates to its
area, next-event estimation, the light tree and bidirectional paths agree with paths alone on
an emitting one, and TOML writes and reads it back. A kind is tested by being registered."""

import itertools

import numpy as np
import pytest

from pathtrace.cameras import PerspectiveCamera
from pathtrace.compiler.compiled import compile_scene
from pathtrace.scene.environment import Environment
from pathtrace.errors import UserError
from pathtrace.materials import Material, pack
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import Mesh, SceneBuilder, diffuse, load_scene
from pathtrace.scene import transform
from pathtrace.scene.toml_writer import scene_toml
from pathtrace.shapes import SHAPES, Shape, TextureUV
from tests.conftest import layout_features, scene_arrays
from tests.stats import z_test
from tests.test_bvh import nearest, nearest_rays, triangle_soup

KINDS = list(SHAPES)


def random_transform(rng, uniform: bool) -> np.ndarray:
    """A random rotation and translation in [-10, 10]^3, scaled by 0.3-1.5 (the same on every
    axis where `uniform`)."""
    axis = rng.normal(size=3)
    scale = rng.uniform(0.3, 1.5) if uniform else rng.uniform(0.3, 1.5, 3)
    return (transform.translation(rng.uniform(-10, 10, 3)) @ transform.rotation(axis, rng.uniform(0, 360))
            @ transform.scaling(np.broadcast_to(scale, 3)))


def shapes_scene(kind, rng, n, triangles=()):
    """n shapes of the kind's examples in turn under random transforms, half of them flipped,
    beside a mesh of `triangles`."""
    b = SceneBuilder()
    m = b.material(diffuse(0.5))
    examples = SHAPES[kind].examples
    for i in range(n):
        b.add_shape(Shape(f"s{i}", kind, examples[i % len(examples)], random_transform(rng, i % 3 == 0), m,
                          flip=bool(i % 2)), keep_kind=True)
    if len(triangles):
        t = np.asarray(triangles, np.float32)
        b.add_mesh(Mesh("soup", t.reshape(-1, 3), np.arange(3 * len(t), dtype=np.int32).reshape(-1, 3), None, m))
    return b.build("shapes")


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("mixed", [False, True])
def test_nearest_hit_matches_brute_force(kernels, kind, mixed):
    """The BVH over the kind's shapes (and a triangle soup) finds the same nearest hit, at the
    same t, as testing every primitive."""
    rng = np.random.default_rng(5)
    tris = triangle_soup(rng, 1500) if mixed else np.zeros((0, 3, 3), np.float32)
    scene = shapes_scene(kind, rng, 1500, tris)
    c = compile_scene(scene)
    assert not c.flat and len(c.shape_prims) == 1500
    centres = np.array([s.to_world[:3, 3] for s in scene.shapes])
    aim_at = np.concatenate([centres, tris.mean(axis=1)]) if mixed else centres
    t_bvh, i_bvh, t_all, i_all = nearest(kernels, c, *nearest_rays(rng, 20000, aim_at))
    np.testing.assert_array_equal(t_bvh, t_all)
    assert np.all((i_bvh == i_all) | (t_bvh == t_all))
    assert np.mean(np.isin(i_all, c.shape_prims)) > 0.2           # the shapes are met


SAMPLE_SOURCE = """
kernel void sample_shape_points(SCENE_KERNEL_ARGS, int num_spheres, int prim, global const float2 *u,
                                global float4 *point, global float4 *params)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int k = get_global_id(0);
    const global Triangle *tri = &sc.triangles[prim - num_spheres];
    const global float4 *f = SHAPE_ROWS(&sc, tri);
    float2 uv;
    float3 n, error;
    float pdf;
    float3 p = sample_analytic(SHAPE_KIND(tri), f, u[k], &uv, &n, &error, &pdf);
    point[k] = (float4)(p, pdf);
    params[k] = (float4)(uv, analytic_params(SHAPE_KIND(tri), f, p));
}
"""


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("uniform", [True, False])
def test_area_sampling_density_integrates_to_the_area(kernels, kind, uniform):
    """The mean of 1 / pdf over sample_analytic's points estimates the shape's world area: under
    a similarity, scale^2 times the kind's closed-form area (every sample's 1 / pdf equals it);
    under a non-uniform scale, the host's integral of the stretch (a Z-test). The points lie on
    the shape: their parameters read back are those sampled."""
    rng = np.random.default_rng(9)
    for example in SHAPES[kind].examples:
        b = SceneBuilder()
        m = transform.rotation([1, 2, 3], 40) @ transform.scaling([1.3, 1.3, 1.3] if uniform else [0.5, 1.7, 1.1])
        b.add_shape(Shape("s", kind, example, m, b.material(diffuse(0.5))), keep_kind=True)
        c = compile_scene(b.build("one"))
        n = 200_000
        u = rng.random((n, 2)).astype(np.float32)
        point, params = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
        kernels(SAMPLE_SOURCE, layout_features(c))("sample_shape_points", n, *scene_arrays(c),
                                                   np.int32(c.num_spheres), np.int32(c.shape_prims[0]), u, point, params)
        inverse = 1.0 / point[:, 3].astype(np.float64)
        assert np.all(np.isfinite(inverse)) and np.all(inverse > 0)
        if uniform:
            np.testing.assert_allclose(inverse, 1.3 ** 2 * SHAPES[kind].area(example), rtol=1e-4)
        else:
            expected = Shape("s", kind, example, m, 0).world_area(SHAPES[kind], samples=4096)
            ok, p, threshold = z_test(np.array([[[inverse.mean()]]]), np.array([[[inverse.var() / n]]]),
                                      np.array([[[expected]]]))
            assert ok, (inverse.mean(), expected, p)
        seam = (params[:, 0] < 1e-3) | (params[:, 0] > 1 - 1e-3)     # u = 0 and 1 are one place
        np.testing.assert_allclose(params[~seam, 2:], params[~seam, :2], atol=2e-3)


def emitter_scene(kind, light_sampler="power"):
    """The kind's first example emitting (radiance 4) 1.5 above a diffuse floor of 32 triangles,
    its object's +z turned to the world's -y, its second example emitting (radiance 0.5) to the
    left, and that example again, diffuse and emitting (radiance 0.5), standing on the floor, in
    a black world: three lights of the kind, between which the light table chooses by power and
    the light tree by their bounds and normal cones, one of them a light that also reflects (as
    pbrt-v4's diffuse area light on any material and Mitsuba 3's area emitter on a shape with a
    BSDF): paths go on from it, light is sampled at points on it, and BDPT's subpaths pass
    through it."""
    b = SceneBuilder()
    x = np.linspace(-3, 3, 5)
    gx, gz = np.meshgrid(x, x, indexing="ij")
    grid = np.stack([gx, np.zeros_like(gx), gz], -1).reshape(-1, 3).astype(np.float32)
    k = np.arange(16).reshape(4, 4)
    i = (k // 4) * 5 + k % 4
    quads = np.stack([i, i + 1, i + 6, i + 5], -1).reshape(-1, 4)
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.int32)
    b.add_mesh(Mesh("floor", grid, faces, None, b.material(diffuse(0.6))))
    lamp = int(b.materials.add_rows(pack("black", {}, emission=np.array([[4.0, 4.0, 4.0]])))[0])
    examples = SHAPES[kind].examples
    down = transform.translation([0, 1.5, 0]) @ transform.rotation([1, 0, 0], 90) @ transform.scaling([0.6] * 3)
    b.add_shape(Shape("lamp", kind, examples[0], down, lamp), keep_kind=True)
    glow = int(b.materials.add_rows(pack("black", {}, emission=np.array([[0.5, 0.5, 0.5]])))[0])
    left = transform.translation([-1.2, 0.9, -0.4]) @ transform.rotation([0, 1, 0], 50) @ transform.scaling([0.4] * 3)
    b.add_shape(Shape("glow", kind, examples[-1], left, glow), keep_kind=True)
    standing = transform.translation([0.8, 0.4, 0.3]) @ transform.rotation([0, 1, 0], 30) @ transform.scaling([0.4] * 3)
    glowing = b.material(Material("diffuse", {"rho_d": 0.8}, emission=np.full(3, 0.5)))
    b.add_shape(Shape("standing", kind, examples[-1], standing, glowing), keep_kind=True)
    scene = b.build(f"{kind} light", camera=PerspectiveCamera([0, 2.2, 4.5], [0, 0.4, 0], [0, 1, 0], 50.0),
                    environment=Environment.constant((0, 0, 0)))
    return scene.with_settings(light_sampler=light_sampler, max_depth=4)


def render(backend, scene, spp, **settings):
    """The mean and per-pixel variance of spp samples, none of them NaN or infinite: the kernels
    drop those (Renderer.dropped_samples), each estimator different ones, which would show as a
    bias between estimators where the cause is the scene or a kernel's NaN."""
    r = Renderer(backend, scene.with_settings(**settings), 32, 24)
    for _ in range(spp // 512):
        r.add_samples(512)
    r.finish()
    assert r.dropped_samples() == 0
    return r.mean(), r.variance()


@pytest.mark.parametrize("kind", KINDS)
def test_an_emitting_shape_with_nee_light_tree_and_bdpt_matches_paths_alone(backend, kind):
    """Paths alone against next-event estimation through the light table, through the light
    tree, and bidirectional paths, on the kind's emitting shapes over a floor, one of them
    diffuse too: a per-pixel Z-test each. Light sampling and MIS use the kind's pdf; BDPT its
    emission and area density. The other estimators draw a quarter of the samples of paths
    alone: their variance, a tenth of its in most pixels, adds little to the difference's."""
    spp, others = 4096, 1024
    m0, v0 = render(backend, emitter_scene(kind), spp, nee=False, seed=1)
    assert m0.mean() > 0.02
    for name, scene, settings in (("nee", emitter_scene(kind), dict(nee=True)),
                                  ("tree", emitter_scene(kind, "tree"), dict(nee=True)),
                                  ("bdpt", emitter_scene(kind), dict(integrator="bdpt"))):
        m1, v1 = render(backend, scene, others, seed=2, **settings)
        ok, p, threshold = z_test(m0, v0 / spp, m1, v1 / others, block=4)
        assert ok, (name, p, threshold)


@pytest.mark.parametrize("kind", KINDS)
def test_the_generic_program_renders_shapes_as_the_scenes_own(backend, kind):
    """The generic program (every kind compiled in, the layout read at run time) renders the
    kind's emitting scene as the scene's own program does, with next-event estimation."""
    from tests.test_programs import same_image, with_mode
    images = []
    for mode in ("generic", "specialised"):
        r = Renderer(with_mode(backend, mode), emitter_scene(kind).with_settings(nee=True, seed=5), 32, 24)
        for _ in range(2):
            r.add_samples(512)
        r.finish()
        images.append(r)
    assert images[0].uses_generic_program and not images[1].uses_generic_program
    same_image(*images)


@pytest.mark.parametrize("kind", KINDS)
def test_toml_writes_and_reads_back_every_shape(tmp_path, kind):
    rng = np.random.default_rng(3)
    scene = shapes_scene(kind, rng, 4)
    for shape, mode in zip(scene.shapes, itertools.cycle(TextureUV)):
        shape.texture_uv = mode
    out = tmp_path / "s.toml"
    out.write_text(scene_toml(scene, out))
    back = load_scene(str(out)).shapes
    assert [s.kind for s in back] == [kind] * 4
    for a, b in zip(scene.shapes, back):      # written to float32's precision, which the kernels take
        np.testing.assert_allclose(b.params, a.params, rtol=1e-6)
        np.testing.assert_allclose(b.to_world, a.to_world, rtol=1e-6, atol=1e-6)
        assert (b.flip, b.texture_uv, b.name) == (a.flip, a.texture_uv, a.name)


@pytest.mark.parametrize("kind", KINDS)
def test_a_bad_shape_is_one_line_naming_the_field(tmp_path, kind):
    path = tmp_path / "bad.toml"
    first = SHAPES[kind].parameters[0].name
    path.write_text(f'[materials]\nm = {{type = "diffuse", rho_d = 0.5}}\n[[shapes]]\nkind = "{kind}"\n'
                    f'{first} = -1\nmaterial = "m"\n')
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    assert "shapes[0]" in str(e.value) and first in str(e.value) and "\n" not in str(e.value)
    path.write_text('[materials]\nm = {type = "diffuse", rho_d = 0.5}\n[[shapes]]\nkind = "blob"\nmaterial = "m"\n')
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    assert "shapes[0].kind" in str(e.value)
    # a scale too small for the kernels' inverse is the file's line, also for a whole sphere (which
    # the file keeps as its kind): it was refused at render as scene.shapes[0], with the matrix
    path.write_text(f'[materials]\nm = {{type = "diffuse", rho_d = 0.5}}\n[[shapes]]\nkind = "{kind}"\n'
                    'material = "m"\nscale = 1e-5\n')
    with pytest.raises(UserError, match=f"bad.toml: shapes\\[0\\]: the transform shrinks or flattens the {kind}"):
        load_scene(str(path))


HIT_SOURCE = """
kernel void shape_hits(SCENE_KERNEL_ARGS, int num_spheres, global const float4 *o, global const float4 *d,
                       global float4 *point, global float4 *normal, global float4 *uv, global float4 *dpdu,
                       global float4 *dpdv)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int k = get_global_id(0);
    Hit h = intersect_scene(&sc, o[k].xyz, d[k].xyz, INFINITY, NO_PRIM);
    if (h.prim < 0) {
        point[k] = (float4)(NAN);
        return;
    }
    Surface s = surface_at(&sc, &h, o[k].xyz, d[k].xyz);
    float3 du, dv;
    surface_derivatives(&sc, &s, &du, &dv);
    point[k] = (float4)(s.p, h.t);
    normal[k] = (float4)(s.ng, 0.0f);
    uv[k] = (float4)(surface_uv(&sc, h.prim, (float2)(h.b1, h.b2), s.p), 0.0f, 0.0f);
    dpdu[k] = (float4)(du, 0.0f);
    dpdv[k] = (float4)(dv, 0.0f);
}
"""


def shape_hits(kernels, scene, origins, targets) -> dict:
    """Where rays from `origins` towards `targets` ((n, 3) world points) meet `scene`: the
    point (NaN: a miss), t, the unit front normal, the texture coordinates, dp/du and dp/dv."""
    c = compile_scene(scene)
    n = len(origins)
    o = np.zeros((n, 4), np.float32)
    d = np.zeros((n, 4), np.float32)
    o[:, :3] = origins
    d[:, :3] = targets - origins
    out = [np.zeros((n, 4), np.float32) for _ in range(5)]
    kernels(HIT_SOURCE, layout_features(c))("shape_hits", n, *scene_arrays(c), np.int32(c.num_spheres), o, d, *out)
    return dict(p=out[0][:, :3], t=out[0][:, 3], n=out[1][:, :3], uv=out[2][:, :2], dpdu=out[3][:, :3],
                dpdv=out[4][:, :3])


def one_shape_scene(shape: Shape):
    """A scene of `shape` alone (its material row 0, diffuse)."""
    b = SceneBuilder()
    b.material(diffuse(0.5))
    b.add_shape(shape, keep_kind=True)
    return b.build("one")
