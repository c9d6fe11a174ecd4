"""Instancing (app/scene/instances.py, app/compiler/two_level.py, kernels/bvh.cl: INSTANCES): the
two-level BVH finds the hits and surfaces the flattened copies have, a ray leaving one
instance's triangle meets the same triangle of another, the readers map pbrt-v4's and Mitsuba
3's instances, scenes of many instances fit and render, and tests/scenes/instances.xml renders
through the two-level BVH as Mitsuba 3 renders it."""

from pathlib import Path

import numpy as np
import pytest
from pyopencl import cltypes

import pathtrace.scene.instances as instancing
from pathtrace.cameras import PerspectiveCamera
from pathtrace.compiler.compiled import compile_scene
from pathtrace.errors import UserError
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import Mesh, SceneBuilder, diffuse, emitter, load_scene
from pathtrace.scene.transform import rotation, scaling, translation
from tests.conftest import KernelRunner, scene_arrays
from tests.stats import z_test

SOURCE = """
kernel void nearest(SCENE_KERNEL_ARGS, int num_spheres, global const float4 *o, global const float4 *d,
                    global float4 *out_p, global float4 *out_n)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int k = get_global_id(0);
    float3 dir = normalize(d[k].xyz);
    Hit h = intersect_scene(&sc, o[k].xyz, dir, INFINITY, NO_PRIM);
    out_p[k] = (float4)(0.0f, 0.0f, 0.0f, -1.0f);
    out_n[k] = (float4)(0.0f);
    if (h.prim < 0)
        return;
    Surface s = surface_at(&sc, &h, o[k].xyz, dir);
    out_p[k] = (float4)(s.p, h.t);
    out_n[k] = (float4)(s.ng, s.offset);
}

#ifdef INSTANCES
/* from below the first surface up, then on from it, leaving it (SURFACE_ID) */
kernel void twice(SCENE_KERNEL_ARGS, int num_spheres, float4 o, global float4 *out)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    float3 up = (float3)(0.0f, 1.0f, 0.0f);
    Hit h = intersect_scene(&sc, o.xyz, up, INFINITY, NO_PRIM);
    Surface s = surface_at(&sc, &h, o.xyz, up);
    Hit g = intersect_scene(&sc, offset_ray_origin(s.p, s.offset, s.ng, up), up, INFINITY, SURFACE_ID(s));
    out[0] = (float4)(h.t, (float)h.prim, (float)h.instance, 0.0f);
    out[1] = (float4)(g.t, (float)g.prim, (float)g.instance, 0.0f);
}
#endif
"""


def transforms(rng, n, spread=8.0):
    """n random transforms: rotations, non-uniform scales (some mirroring), translations."""
    out = []
    for k in range(n):
        s = rng.uniform(0.5, 1.6, 3) * np.where(rng.random(3) < 0.15, -1, 1)
        m = translation(rng.uniform(-spread, spread, 3)) @ rotation(rng.normal(size=3), rng.uniform(0, 360)) @ scaling(s)
        out.append(m)
    return out


def instanced_scene(rng, n_instances=60, n_objects=3):
    """World spheres and a floor, and objects of triangle soups drawn by random instances."""
    b = SceneBuilder()
    m = b.material(diffuse(0.5))
    for c in rng.uniform(-8, 8, (10, 3)):
        b.add_sphere(c, 0.6, m)
    floor = np.array([[-10, -9, -10], [10, -9, -10], [10, -9, 10], [-10, -9, 10]], np.float32)
    b.add_mesh(Mesh("floor", floor, np.array([[0, 2, 1], [0, 3, 2]], np.int32), None, m))
    for k in range(n_objects):
        obj = b.add_object(f"object {k}")
        corners = (rng.uniform(-1, 1, (40, 1, 3)) + rng.normal(scale=0.4, size=(40, 3, 3))).astype(np.float32)
        b.objects[obj].meshes.append(Mesh(f"soup {k}", corners.reshape(-1, 3),
                                          np.arange(120, dtype=np.int32).reshape(-1, 3), None, m))
    for k, t in enumerate(transforms(rng, n_instances)):
        b.add_instance(k % n_objects, t)
    return b.build("instances")


def shoot(backend, scene, o, d, two_level, monkeypatch):
    monkeypatch.setattr(instancing, "FLATTEN_MAX", -1 if two_level else 1 << 40)
    c = compile_scene(scene)
    assert c.two_level == two_level
    runner = KernelRunner(backend, SOURCE, c.features(scene.settings, scene.camera))
    p, n = np.zeros((len(o), 4), np.float32), np.zeros((len(o), 4), np.float32)
    runner("nearest", len(o), *scene_arrays(c), np.int32(c.num_spheres), o, d, p, n)
    return p, n


def test_the_two_level_bvh_finds_what_the_flattened_copies_show(backend, monkeypatch):
    """The nearest hit's distance, point and geometric normal, for rays at random and rays
    aimed at the instances, against the one-level BVH over the instances' world-space copies
    (whose faces turn round where a transform mirrors)."""
    rng = np.random.default_rng(7)
    scene = instanced_scene(rng)
    n = 20000
    o = np.column_stack([rng.uniform(-12, 12, (n, 3)), np.zeros(n)]).astype(np.float32)
    targets = scene.instances.to_world[rng.integers(0, len(scene.instances), n), :3, 3] + rng.normal(scale=1.0, size=(n, 3))
    d = np.column_stack([targets - o[:, :3], np.zeros(n)]).astype(np.float32)
    p1, n1 = shoot(backend, scene, o, d, False, monkeypatch)
    p2, n2 = shoot(backend, scene, o, d, True, monkeypatch)
    hit1, hit2 = p1[:, 3] >= 0, p2[:, 3] >= 0
    assert hit1.mean() > 0.5
    assert np.mean(hit1 != hit2) < 2e-3                       # rays grazing an edge may differ
    both = hit1 & hit2
    same = np.abs(p1[both, 3] - p2[both, 3]) <= 1e-4 * p1[both, 3]
    assert same.mean() > 0.998
    np.testing.assert_allclose(p2[both][same, :3], p1[both][same, :3], atol=2e-3)
    cos = np.sum(n1[both][same, :3] * n2[both][same, :3], axis=1)
    assert np.mean(cos > 0.9999) > 0.998
    # every error offset is positive and small beside the scene (the transformed bound)
    assert np.all(n2[both, 3] > 0) and np.all(n2[both, 3] < 1e-2)


def test_a_ray_leaving_one_instance_meets_the_same_triangle_of_the_next(backend, monkeypatch):
    """The surface a ray leaves is a triangle of one instance: the same triangle drawn by an
    instance just above is met, not skipped as the surface left behind."""
    b = SceneBuilder()
    m = b.material(diffuse(0.5))
    obj = b.add_object("sheet")
    b.objects[obj].meshes.append(Mesh("sheet", np.array([[-1, 0, -1], [1, 0, -1], [0, 0, 1]], np.float32),
                                      np.array([[0, 2, 1]], np.int32), None, m))
    b.add_instance(obj, np.eye(4))
    b.add_instance(obj, translation((0, 1e-3, 0)))
    scene = b.build("sheets")
    monkeypatch.setattr(instancing, "FLATTEN_MAX", -1)
    c = compile_scene(scene)
    runner = KernelRunner(backend, SOURCE, c.features(scene.settings, scene.camera))
    out = np.zeros((2, 4), np.float32)
    runner("twice", 1, *scene_arrays(c), np.int32(c.num_spheres), cltypes.make_float4(0, -1, 0, 0), out)
    (t1, prim1, inst1, _), (t2, prim2, inst2, _) = out
    assert t1 == pytest.approx(1.0, rel=1e-5) and prim2 == prim1 and inst2 != inst1
    assert t2 == pytest.approx(1e-3, rel=0.05)


def test_a_hundred_thousand_instances_fit_and_render(backend, monkeypatch):
    """1e5 instances of a 2000-triangle object (2e8 triangles flattened: some 20 GB with their
    BVH) compile to a few megabytes and render a lit, finite image."""
    rng = np.random.default_rng(3)
    b = SceneBuilder()
    m = b.material(diffuse(0.7))
    obj = b.add_object("soup")
    corners = rng.normal(scale=0.3, size=(2000, 3, 3)).astype(np.float32)
    b.objects[obj].meshes.append(Mesh("soup", corners.reshape(-1, 3), np.arange(6000, dtype=np.int32).reshape(-1, 3),
                                      None, m))
    n = 100_000
    t = np.tile(np.eye(4), (n, 1, 1))
    t[:, :3, 3] = rng.uniform((-100, -2, -100), (100, 2, 100), (n, 3))      # a field under the sky
    for k in range(n):
        b.add_instance(obj, t[k])
    # seen from above, under the sky: the walks through the field find lit surfaces in many
    # pixels (from inside the field, at the default camera, nearly every path stayed dark)
    scene = b.build("forest", camera=PerspectiveCamera([0, 12, 0], [0, 0, 0], [0, 0, 1], 60.0))
    assert scene.instances.triangle_count == 2 * 10 ** 8
    c = compile_scene(scene)
    assert c.two_level and c.num_triangles == 2000 and len(c.instances) == n
    assert sum(a.nbytes for a in c.geometry_arrays().values()) < 32 << 20
    r = Renderer(backend, scene, 32, 18)
    r.add_samples(2)
    r.finish()
    img = r.mean()
    lit = np.mean(img.max(-1) > 0)          # 0.43 at 2 samples per pixel (PoCL, 2026-11-29)
    assert np.all(np.isfinite(img)) and lit > 0.2


REFERENCE = Path(__file__).parent / "references" / "instances.npz"


def test_instances_render_through_the_two_level_bvh_as_mitsuba_renders_them(backend, monkeypatch):
    """tests/scenes/instances.xml (shapegroups drawn through rotations, a non-uniform scale and
    a mirror; a textured cube and an anisotropic fin in them) against Mitsuba 3's render."""
    monkeypatch.setattr(instancing, "FLATTEN_MAX", -1)
    ref = np.load(REFERENCE)
    h, w, _ = ref["mean"].shape
    scene = load_scene(str(Path(__file__).parent / "scenes" / "instances.xml"))
    scene = scene.with_settings(max_depth=int(ref["max_depth"]), russian_roulette="off", nee=True)
    r = Renderer(backend, scene, w, h)
    assert r.compiled.two_level
    for _ in range(32):
        r.add_samples(128)
    r.finish()
    ok, p, threshold = z_test(r.mean(), r.variance() / r.samples, ref["mean"], ref["var_of_mean"], block=4,
                              rel_floor=1e-5)
    assert ok, f"smallest p-value {p:.3g} below the Sidak threshold {threshold:.3g}"


def test_bad_pbrt_instances_are_one_line(tmp_path):
    (tmp_path / "s.pbrt").write_text('Camera "perspective"\nWorldBegin\nObjectInstance "nothing"\n')
    with pytest.raises(UserError) as e:
        load_scene(str(tmp_path / "s.pbrt"))
    assert "no object named" in str(e.value) and "s.pbrt" in str(e.value) and "\n" not in str(e.value)


def test_a_pbrt_instance_under_a_singular_transform_is_left_out_with_a_warning(tmp_path, capsys):
    """As pbrt-v4 takes the transform (an inverse of infinities), not refused; what it would draw
    is flat (docs/pbrt.md)."""
    (tmp_path / "s.pbrt").write_text(
        'Camera "perspective"\nWorldBegin\nShape "sphere"\n'
        'ObjectBegin "a"\nShape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]\nObjectEnd\n'
        'Transform [1 0 0 0  2 0 0 0  0 0 1 0  0 0 0 1]\nObjectInstance "a"\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert s.instances is None and s.triangle_count == 0
    assert "s.pbrt:8: the current transform is singular" in capsys.readouterr().err


@pytest.mark.parametrize("name,text,where", [
    ("s.pbrt", 'Camera "perspective"\nWorldBegin\nObjectBegin "a"\n'
     'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]\nObjectEnd\n'
     'Scale 1e-11 1e-11 1e-11\nObjectInstance "a"\n', "s.pbrt:7: "),
    ("s.xml", '<scene version="3.0.0">\n<shape type="sphere"/>\n<shape type="shapegroup" id="g"><shape type="cube"/></shape>\n'
     '<shape type="instance"><ref id="g"/><transform name="to_world"><scale value="1e-11"/></transform></shape>\n'
     '</scene>', "s.xml:4: "),
    ("s.toml", '[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = { type = "diffuse", rho_d = 0.5 }\n'
     '[[objects.o.meshes]]\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nfaces = [[0, 1, 2]]\n'
     'material = { type = "diffuse", rho_d = 0.5 }\n[[instances]]\nobject = "o"\nscale = [1e-11, 1e-11, 1e-11]\n',
     "s.toml: instances[0]: "),
])
def test_an_instance_too_near_singular_is_refused_where_the_file_gives_it(tmp_path, name, text, where):
    # its determinant, 1e-33, is below instancing.MIN_DETERMINANT but its inverse is finite: the
    # readers refuse it with the file's place, not the renderer with an instance's number
    (tmp_path / name).write_text(text)
    with pytest.raises(UserError) as e:
        load_scene(str(tmp_path / name))
    message = str(e.value)
    assert where in message and "too near singular" in message and "1e-33" in message and "\n" not in message, message


@pytest.mark.parametrize("body,problem", [
    ('<shape type="instance"><transform name="to_world"><translate x="1"/></transform></shape>', "shapegroup"),
    ('<shape type="shapegroup" id="g"><shape type="cube"/></shape>'
     '<shape type="shapegroup" id="h"><shape type="instance"><ref id="g"/></shape></shape>'
     '<shape type="instance"><ref id="h"/></shape>', "cannot hold shapegroups or instances"),
])
def test_bad_mitsuba_instances_are_one_line(tmp_path, body, problem):
    (tmp_path / "s.xml").write_text(f'<scene version="3.0.0"><shape type="sphere"/>{body}</scene>')
    with pytest.raises(UserError) as e:
        load_scene(str(tmp_path / "s.xml"))
    assert problem in str(e.value) and "\n" not in str(e.value)


def test_instances_the_api_makes_are_checked():
    b = SceneBuilder()
    m = b.material(diffuse(0.5))
    obj = b.add_object("tri")
    b.objects[obj].meshes.append(Mesh("tri", np.eye(3, dtype=np.float32), np.array([[0, 1, 2]], np.int32), None, m))
    b.add_instance(obj, np.diag([1.0, 0.0, 1.0, 1.0]))
    with pytest.raises(UserError, match="instance 0: its transform is not finite, affine and invertible"):
        compile_scene(b.build("bad"))
    b.instance_to_world[0] = np.eye(4)
    b.objects[obj].meshes[0].material = b.material(emitter(1.0))
    with pytest.raises(UserError, match="mesh 'tri' of an instanced object emits"):
        compile_scene(b.build("bright"))


def test_convert_writes_objects_and_instances_that_read_back_the_same(tmp_path):
    from pathtrace.cli.main import main
    xml = Path(__file__).parent / "scenes" / "instances.xml"
    out = tmp_path / "instances.toml"
    assert main(["convert", str(xml), "-o", str(out)]) == 0
    a, b = load_scene(str(xml)), load_scene(str(out))
    np.testing.assert_array_equal(a.instances.object, b.instances.object)
    np.testing.assert_allclose(a.instances.to_world, b.instances.to_world)
    for oa, ob in zip(a.instances.objects, b.instances.objects):
        assert oa.name == ob.name and len(oa.meshes) == len(ob.meshes)
        for ma, mb in zip(oa.meshes, ob.meshes):
            np.testing.assert_allclose(ma.vertices, mb.vertices, rtol=1e-6)
            np.testing.assert_array_equal(ma.faces, mb.faces)
    assert len(a.spheres) == len(b.spheres) == 3        # the lamp and the balls' copies


@pytest.mark.parametrize("body,problem", [
    ('[[instances]]\nobject = "nothing"\n', "instances[0].object: must name an entry of [objects]"),
    ('[[objects.lamp.meshes]]\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nfaces = [[0, 1, 2]]\n'
     'material = { type = "emitter", Le = [1, 1, 1] }\n[[instances]]\nobject = "lamp"\n', "cannot emit"),
    ('[[objects.far.meshes]]\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nfaces = [[0, 1, 2]]\n'
     'material = { type = "diffuse", rho_d = 0.5 }\n[[instances]]\nobject = "far"\nscale = 1e30\n',
     "instance 0 reaches beyond 1e+18"),
])
def test_bad_toml_instances_are_one_line(tmp_path, body, problem):
    (tmp_path / "s.toml").write_text('[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = { type = "diffuse", '
                                     'rho_d = 0.5 }\n' + body)
    with pytest.raises(UserError) as e:
        compile_scene(load_scene(str(tmp_path / "s.toml")))       # copied into the world or not
    assert problem in str(e.value) and "\n" not in str(e.value)


def test_a_scene_of_instances_alone_has_bounds_round_them():
    """Scene.bounds() takes the instances in: a box holding each instance's triangles in world
    space (their copies'), the repr says so, one instance in the singular."""
    b = SceneBuilder()
    m = b.material(diffuse(0.5))
    obj = b.add_object("tri")
    b.objects[obj].meshes.append(Mesh("tri", np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32),
                                      np.array([[0, 1, 2]], np.int32), None, m))
    b.add_instance(obj, translation([5, 0, 0]))
    scene = b.build("one")
    lower, upper = scene.bounds()
    corners = np.concatenate([mesh.vertices for mesh in instancing.flattened_meshes(scene.instances)])
    assert np.all(lower <= corners.min(0)) and np.all(upper >= corners.max(0))
    np.testing.assert_allclose([lower, upper], [[5, 0, 0], [6, 1, 0]])
    assert "1 instance (1 triangle)" in repr(scene) and "empty" not in repr(scene)
