"""Bidirectional path tracing (kernels/bdpt.cl) and its light tracing alone (the integrator
"ptracer"): each converges to the path tracer's image and to closed forms, in participating
media too, and for fixed paths the MIS weights of all the strategies that can draw a path sum
to 1."""

from dataclasses import replace

import numpy as np
import pyopencl as cl
import pytest

from pathtrace.cameras import CAMERAS
from pathtrace.device.opencl import build_program
from pathtrace.errors import UserError
from pathtrace.filters import PixelFilter
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.scene.toml_reader import read_scene_dict
from tests.commands import in_process
from tests.conftest import ROOT
from tests.scene_files import SCENE_FILES, SCENE_SIZE
from tests.stats import blocks_and_image, variance_of_means, z_test, z_test_of

BATCHES = 6    # independent renders (seeds) whose spread gives a BDPT pixel's variance: its
               # sums of squares hold the camera subpaths' part alone (the splats are shared)


def render_batches(backend, scene, integrator, spp, size, batches=BATCHES):
    """`batches` renders of `spp` samples per pixel, each of its own seed: (batches, H, W, 3)."""
    means = []
    for k in range(batches):
        r = Renderer(backend, scene.with_settings(integrator=integrator, seed=1000 * k + 7), *size)
        r.add_samples(spp)
        r.finish()
        assert r.dropped_samples() == 0     # a NaN dropped would show as a bias, not as what it is
        means.append(r.mean())
    return np.array(means, np.float64)


def render(backend, scene, integrator, spp, size, batches=BATCHES):
    """The mean of `batches` renders of `spp` samples per pixel, and each pixel's variance of
    that mean, from the renders' spread."""
    means = render_batches(backend, scene, integrator, spp, size, batches)
    return means.mean(0), means.var(0, ddof=1) / batches


def path_reference(backend, make, spp, size):
    """The path tracer's image (with next-event estimation) of scene make() and its variance of
    the mean, from its per-pixel sample variance; once per scene, for the cases that share it."""
    key = make, spp, size
    if key not in _PATH_REFERENCES:
        _PATH_REFERENCES[key] = _path_reference(backend, make(), spp, size)
    return _PATH_REFERENCES[key]


_PATH_REFERENCES = {}


def _path_reference(backend, scene, spp, size):
    r = Renderer(backend, scene.with_settings(integrator="path", seed=99), *size)
    for _ in range(spp // 256):
        r.add_samples(256)
    r.finish()
    assert r.dropped_samples() == 0
    return r.mean().astype(np.float64), r.variance().astype(np.float64) / r.samples


RHO = 0.6
LAMP = {"type": "emitter", "Le": [8.0, 7.2, 6.0]}


def floor_scene(lights=(), objects=(), materials=None, max_depth=5, camera=None, meshes=(), media=None,
                environment=None):
    """A diffuse floor (y = 0) of albedo RHO under `lights`, with `objects` (spheres) and
    `meshes` on it, in a black world (or `environment`), seen by a pinhole."""
    return read_scene_dict({
        "camera": camera or {"eye": [0, 2.2, 3.2], "look_at": [0, 0.4, 0], "up": [0, 1, 0], "vfov": 40},
        "environment": environment or {"color": 0},
        "render": {"max_depth": max_depth, "russian_roulette": "off"},
        "materials": {"floor": {"type": "diffuse", "rho_d": RHO}, **(materials or {})},
        "media": media or {},
        "meshes": [{"vertices": [[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]], "faces": [[0, 3, 2, 1]],
                    "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]], "material": "floor"}, *meshes],
        "spheres": list(objects), "lights": list(lights)}, "floor")


def glass_scene():
    """A glass sphere on the floor under a spherical lamp: a caustic, a path the path tracer finds
    only by chance (floor -> glass -> glass -> lamp). The lamp is large enough that its image in
    the glass is not so rare an event that a few renders' spread misjudges its variance."""
    return floor_scene(objects=[{"center": [0, 0.5, 0], "radius": 0.5, "material": "glass"},
                                {"center": [0.4, 2.0, -0.3], "radius": 0.3, "material": "lamp"},
                                {"center": [-0.9, 0.3, 0.2], "radius": 0.3, "material": "metal"}],
                       materials={"glass": {"type": "dielectric"}, "lamp": LAMP,
                                  "metal": {"type": "roughconductor", "material": "Au", "alpha": 0.3}})


def sky_scene():
    """A diffuse and a glossy sphere on the floor under a sunset's map: light from the
    environment, which starts light subpaths from a disk across the scene, and paths that escape
    to it after bounces."""
    return floor_scene(objects=[{"center": [0, 0.5, 0], "radius": 0.5, "material": "white"},
                                {"center": [-0.9, 0.3, 0.2], "radius": 0.3, "material": "metal"}],
                       materials={"white": {"type": "diffuse", "rho_d": 0.8},
                                  "metal": {"type": "roughconductor", "material": "Au", "alpha": 0.3}},
                       environment={"map": "venice_sunset_1k.hdr", "rotation": 200})


def goniometric_scene():
    """A goniometric light over the floor and a sphere: a delta light whose intensity an image
    gives, which light subpaths leave in every direction."""
    return floor_scene(lights=[{"type": "goniometric", "position": [0.1, 1.2, -0.2], "intensity": [3.0, 2.0, 1.0],
                                "up": [0.3, -1.0, 0.2], "image": str(ROOT / "assets" / "textures" / "tiles.png")}],
                       objects=[{"center": [0, 0.5, 0], "radius": 0.5, "material": "white"}],
                       materials={"white": {"type": "diffuse", "rho_d": 0.8}})


PROJECTION = {"type": "projection", "position": [0.1, 1.6, 0.3], "direction": [0, -1, -0.2], "up": [0, 0, -1],
              "fov": 60, "scale": 2.0, "image": str(ROOT / "assets" / "textures" / "tiles.png")}


def projection_scene():
    """A projection light's image on the bare floor: a delta light whose light subpaths leave
    through its screen. (With a sphere on the floor, the floor behind it is lit only by paths so
    rare that the path tracer's 1,024 samples find none there, and its zero variance fails the
    test where BDPT's light tracing finds them.)"""
    return floor_scene(lights=[PROJECTION])


def spot_scene():
    """A spot and a point light over the floor, a diffuse and a glossy sphere: delta lights,
    which light subpaths start from and no camera subpath hits."""
    return floor_scene(
        lights=[{"type": "spot", "position": [0.5, 2.0, 0.8], "look_at": [0, 0, 0], "intensity": 6.0,
                 "cutoff_angle": 35.0},
                {"type": "point", "position": [-1.0, 1.5, -0.5], "intensity": [1.0, 2.0, 3.0]}],
        objects=[{"center": [0.3, 0.4, 0], "radius": 0.4, "material": "white"},
                 {"center": [-0.6, 0.3, 0.4], "radius": 0.3, "material": "plastic"}],
        materials={"white": {"type": "diffuse", "rho_d": 0.8},
                   "plastic": {"type": "roughplastic", "diffuse_reflectance": 0.3, "alpha": 0.2}})


def fog_scene(lights, objects):
    """Fog in a box that is no surface, on the floor, with `objects` and `light` in it and the
    camera outside: camera subpaths, light subpaths and connections cross the box, and free
    flights scatter in the fog, which is bluer (thicker) than it is red."""
    box = np.array([[x, y, z] for x in (-1.6, 1.6) for y in (-0.1, 2.4) for z in (-1.6, 1.6)])
    faces = []
    for quad in ([0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]):
        v = box[quad]
        outward = np.dot(np.cross(v[1] - v[0], v[2] - v[0]), v.mean(0) - box.mean(0)) > 0
        faces.append(quad if outward else quad[::-1])      # the front, the exterior's side, faces out
    return floor_scene(lights=lights, objects=objects,
                       camera={"eye": [0.3, 1.5, 4.6], "look_at": [0, 0.8, 0], "up": [0, 1, 0], "vfov": 40},
                       materials={"white": {"type": "diffuse", "rho_d": 0.8}, "glass": {"type": "dielectric"},
                                  "lamp": LAMP, "air": {"type": "null"}},
                       meshes=[{"vertices": box.tolist(), "faces": faces, "material": "air", "interior": "fog"}],
                       media={"fog": {"sigma_a": 0.05, "sigma_s": [0.25, 0.3, 0.4], "g": 0.3}})


def fog_point_scene():
    """A point light in the fog, which its light subpaths find themselves in by the boundaries
    between it and the camera, over a diffuse sphere with the fog outside it."""
    return fog_scene(lights=[{"type": "point", "position": [0.5, 1.9, -0.4], "intensity": 2.0}],
                     objects=[{"center": [0, 0.5, 0], "radius": 0.5, "material": "white", "exterior": "fog"}])


def fog_lamp_scene():
    """A spherical lamp in the fog that bounds nothing, over a diffuse sphere with the fog
    outside it."""
    return fog_scene(lights=(), objects=[{"center": [0, 0.5, 0], "radius": 0.5, "material": "white", "exterior": "fog"},
                                         {"center": [0.5, 1.9, -0.4], "radius": 0.2, "material": "lamp"}])


def fog_glass_scene():
    """A volumetric caustic: a spherical lamp and a glass sphere in the fog, whose surfaces bound
    it (a light subpath leaves the lamp into the medium on its outside); the glass focuses the
    lamp's light into the fog below it."""
    return fog_scene(lights=(), objects=[{"center": [0, 0.8, 0], "radius": 0.45, "material": "glass", "exterior": "fog"},
                                         {"center": [0.2, 1.9, -0.2], "radius": 0.25, "material": "lamp",
                                          "exterior": "fog"}])


def pool_scene(floor=None):
    """A pool: its floor seen through a flat water surface and lit through it by a lamp above, every
    path to it specular-diffuse-specular (E S D S L), which BDPT finds only as the path tracer does,
    by a camera subpath that happens to hit the lamp: caustic photons estimate them. The lamp is
    large enough for the path tracer to converge there. A smooth plastic sphere under the water
    mirrors some of the light on to the floor: light subpaths that land on it and then on the
    floor, one photon chosen of the two."""
    return floor_scene(objects=[{"center": [0.3, 1.6, -0.4], "radius": 0.35, "material": "lamp"},
                                {"center": [-0.3, 0.2, 0.1], "radius": 0.2, "material": "plastic"}],
                       meshes=[{"vertices": [[-1.2, 0.4, -1.2], [1.2, 0.4, -1.2], [1.2, 0.4, 1.2], [-1.2, 0.4, 1.2]],
                                "faces": [[0, 3, 2, 1]], "material": "water"}],
                       materials={"lamp": LAMP, "water": {"type": "dielectric", "int_ior": 1.33},
                                  "plastic": {"type": "plastic", "diffuse_reflectance": 0.5, "int_ior": 3.0},
                                  **({"floor": floor} if floor else {})},
                       camera={"eye": [0, 2.0, 1.6], "look_at": [0, 0, 0], "up": [0, 1, 0], "vfov": 50}
                       ).with_settings(photon_radius=0.08)


NORMAL_MAP = {"type": "bitmap", "file": str(ROOT / "tests/scenes/textures/normals.png"), "raw": True}


def normal_maps(**extra) -> dict:
    """A normal-mapped diffuse floor and back wall under a low lamp, as a scene dictionary, with
    `extra` materials, spheres or camera."""
    normals = NORMAL_MAP | {"uv_scale": [4, 4]}
    quad = [[0, 0], [1, 0], [1, 1], [0, 1]]
    return {
        "camera": extra.get("camera", {"eye": [0, 2.5, 3], "look_at": [0, 0.5, -0.5], "up": [0, 1, 0], "vfov": 50}),
        "environment": {"color": 0},
        "render": {"max_depth": 5, "russian_roulette": "off"},
        "materials": {"floor": {"type": "diffuse", "rho_d": RHO, "normal_map": normals},
                      "wall": {"type": "diffuse", "rho_d": 0.8, "normal_map": normals}, "lamp": LAMP,
                      **{name: {**m, "normal_map": normals} for name, m in extra.get("materials", {}).items()}},
        "meshes": [{"vertices": [[-3, 0, -2], [3, 0, -2], [3, 0, 3], [-3, 0, 3]], "faces": [[0, 3, 2, 1]],
                    "uvs": quad, "material": "floor"},
                   {"vertices": [[-3, 0, -2], [3, 0, -2], [3, 3, -2], [-3, 3, -2]], "faces": [[0, 1, 2, 3]],
                    "uvs": quad, "material": "wall"}],
        "spheres": [{"center": [2.2, 0.5, -1.0], "radius": 0.3, "material": "lamp"}, *extra.get("spheres", [])]}


def normal_map_scene():
    """Mitsuba's normal maps, whose BSDF is not reciprocal (normal_maps), under grazing light that
    the perturbed normals face away from in places. The path tracer turns a perturbed normal by
    the camera's side (kernels/normal_maps.cl: face_perturbed_normal), which BDPT's light
    subpaths learn only when joined (kernels/bdpt_vertex.cl: seen_from); light that the floor
    reflects onto the wall, and the wall onto the floor, is drawn in a frame a light subpath
    chooses before its direction (frame_probability). Nothing casts a shadow, where light
    tracing's few splats would misjudge their variance."""
    return read_scene_dict(normal_maps(), "normal-maps")


def normal_map_glass_scene():
    """normal_maps with a normal-mapped glass sphere, seen from above the floor in front of it,
    where its caustic falls: a light subpath's frame, drawn for the camera's side, leaves the
    side light arrives from to be tested against the geometric normal, which a refraction would
    otherwise read as light from inside."""
    return read_scene_dict(normal_maps(materials={"glass": {"type": "dielectric"}},
                                       spheres=[{"center": [0.8, 0.6, -0.6], "radius": 0.6, "material": "glass"}],
                                       camera={"eye": [0, 3, 3.5], "look_at": [0, 0, 1.5], "up": [0, 1, 0],
                                               "vfov": 30}), "normal-maps-glass")


def lampshade_scene():
    """A diffuse-transmission panel seen through water and lit from below through glass by a
    lamp: every path to the lamp crosses the panel between delta bounces, which caustic photons
    estimate from the panel's other side (BDPT with photons rendered 2 % of the path tracer's
    image when the gather kept only photons on the camera's side)."""
    def quad(y, material, size=1.5):
        return {"vertices": [[-size, y, -size], [size, y, -size], [size, y, size], [-size, y, size]],
                "faces": [[0, 3, 2, 1]], "material": material}
    return read_scene_dict({
        "camera": {"eye": [0, 2.0, 1.2], "look_at": [0, 0, 0], "up": [0, 1, 0], "vfov": 45},
        "environment": {"color": 0}, "render": {"max_depth": 6, "russian_roulette": "off"},
        "materials": {"water": {"type": "dielectric", "int_ior": 1.33}, "glass": {"type": "dielectric", "int_ior": 1.5},
                      "panel": {"type": "diffusetransmission", "reflectance": 0.1, "transmittance": 0.8}, "lamp": LAMP},
        "meshes": [quad(0.5, "water", 3), quad(0.2, "panel"), quad(0.0, "glass", 3)],
        "spheres": [{"center": [0.2, -0.8, 0.1], "radius": 0.5, "material": "lamp"}]}, "lampshade"
    ).with_settings(photon_radius=0.05)


def normal_mapped_pool_scene():
    """pool_scene with a normal-mapped floor: the photons' density is per area of the geometric
    normal, which the path tracer's cosine with the shading normal corrects (photons.cl:
    gather_photons; 32 % bright without that). The map's texels are wider than the photons'
    radius, whose blur over finer ones (0.9 % at 30 tiles) would leave the test no margin."""
    return pool_scene({"type": "diffuse", "rho_d": RHO, "normal_map": NORMAL_MAP | {"uv_scale": [8, 8]}})


def media_fog():
    """Mitsuba's fog room: the camera in the fog, a spot light outside it (tests/scenes)."""
    return load_scene(str(ROOT / "tests/scenes/media-fog.xml")).with_settings(filter=PixelFilter(), max_depth=5)


def cbox():
    return load_scene(str(ROOT / "tests/scenes/cbox.xml")).with_settings(filter=PixelFilter(), max_depth=5)


def cbox_gaussian():
    """The Cornell box through Mitsuba's default pixel filter, a gaussian of radius 2: light
    tracing's splats spread over 5 x 5 pixels by the filter's density."""
    return cbox().with_settings(filter=PixelFilter("gaussian"))


def cbox_thinlens():
    """The Cornell box through a thin lens focused before the back wall: light tracing joins each
    vertex to a point of the aperture."""
    scene = cbox()
    camera = scene.camera.as_type("thinlens", aperture_radius=0.15, focus_distance=3.0)
    return replace(scene, camera=camera)


# (scene, the integrator against the path tracer, its samples per pixel per batch, the path
# tracer's samples per pixel): the Cornell box's diffuse walls with light tracing alone and
# with BDPT, through a box and a gaussian filter and a thin lens; glass, gold and a caustic;
# delta lights. The path tracer's variance of the mean at 1024 samples per pixel is, in the
# median pixel, 11-20 % of the tested estimator's (cbox with ptracer, bdpt and the thin lens;
# spot), 39 % through the gaussian filter (measured on PoCL, 2026-11-29): the difference's
# standard error is 5-18 % above the tested estimator's alone. The caustic's reference keeps
# 4096, for its sample variance to have seen the rare paths through the glass.
CASES = {"cbox-ptracer": (cbox, "ptracer", 32, 1024), "cbox-bdpt": (cbox, "bdpt", 16, 1024),
         "cbox-gaussian-ptracer": (cbox_gaussian, "ptracer", 32, 1024),
         "cbox-thinlens-ptracer": (cbox_thinlens, "ptracer", 32, 1024),
         "glass-bdpt": (glass_scene, "bdpt", 16, 4096), "spot-bdpt": (spot_scene, "bdpt", 16, 1024),
         "fog-lamp-bdpt": (fog_lamp_scene, "bdpt", 16, 1024), "fog-lamp-ptracer": (fog_lamp_scene, "ptracer", 32, 1024),
         "fog-glass-bdpt": (fog_glass_scene, "bdpt", 16, 4096), "media-fog-bdpt": (media_fog, "bdpt", 16, 1024),
         "pool-photons-bdpt": (pool_scene, "bdpt", 16, 4096), "sky-bdpt": (sky_scene, "bdpt", 16, 1024),
         "goniometric-bdpt": (goniometric_scene, "bdpt", 16, 1024),
         "projection-bdpt": (projection_scene, "bdpt", 16, 1024),
         "projection-ptracer": (projection_scene, "ptracer", 32, 1024),
         "normal-maps-bdpt": (normal_map_scene, "bdpt", 16, 1024),
         "normal-maps-ptracer": (normal_map_scene, "ptracer", 32, 1024),
         "pool-normal-map-photons-bdpt": (normal_mapped_pool_scene, "bdpt", 16, 4096),
         "lampshade-photons-bdpt": (lampshade_scene, "bdpt", 16, 4096)}
SIZE = (24, 24)


@pytest.mark.parametrize("case", list(CASES))
def test_converges_to_the_path_tracer(backend, case):
    make, integrator, spp, path_spp = CASES[case]
    scene = make()
    m, v = render(backend, scene, integrator, spp, SIZE)
    ref, ref_v = path_reference(backend, make, path_spp, SIZE)
    assert np.all(np.isfinite(m))
    ok, p, threshold = z_test(m, v, ref, ref_v, block=4)     # its blocks and the whole image's mean
    assert ok, (p, threshold)


def test_light_traced_through_normal_mapped_glass_is_the_path_tracers(backend):
    """The floor lit through a normal-mapped glass sphere (normal_map_glass_scene), by light
    tracing alone against the path tracer, the image's mean: light subpaths drew light arriving
    below their frame at the glass as light from inside, 7.6 % bright (z 7.6) before they tested
    it (a review's measurement, 2026-11-30). The caustic's few splats leave the blocks' variance
    to chance, so the test takes the image's mean over many batches."""
    m = render_batches(backend, normal_map_glass_scene(), "ptracer", 256, SIZE, 40)[..., :3].mean(axis=(1, 2, 3))
    ref, ref_v = path_reference(backend, normal_map_glass_scene, 16384, SIZE)
    z = (m.mean() - ref[..., :3].mean()) / np.sqrt(m.var(ddof=1) / len(m) + ref_v[..., :3].sum() / ref[..., :3].size ** 2)
    assert abs(z) < 4, (m.mean() / ref[..., :3].mean(), z)


def low_poly_sphere_obj(path, stacks=5, slices=8, radius=0.5, centre=(0.0, 0.5, 0.0)):
    """An OBJ file of a sphere of few faces whose vertex normals are the sphere's: shading
    normals far from the geometric ones."""
    c = np.array(centre)
    rings = [(np.sin(np.pi * i / stacks), np.cos(np.pi * i / stacks)) for i in range(1, stacks)]
    points = [c + [0, radius, 0]] + [c + radius * np.array([s * np.cos(2 * np.pi * j / slices), h,
                                                            -s * np.sin(2 * np.pi * j / slices)])
                                     for s, h in rings for j in range(slices)] + [c - [0, radius, 0]]
    at = lambda i, j: 2 + (i - 1) * slices + j % slices     # noqa: E731  (OBJ indices from 1)
    faces = ([(1, at(1, j), at(1, j + 1)) for j in range(slices)]
             + [(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)) for i in range(1, stacks - 1) for j in range(slices)]
             + [(len(points), at(stacks - 1, j + 1), at(stacks - 1, j)) for j in range(slices)])
    lines = [f"v {p[0]} {p[1]} {p[2]}" for p in points]
    lines += ["vn {} {} {}".format(*((p - c) / radius)) for p in points]
    lines += ["f " + " ".join(f"{k}//{k}" for k in face) for face in faces]
    path.write_text("\n".join(lines) + "\n")


def test_bdpt_through_smooth_shaded_rough_glass_is_the_path_tracers(backend, tmp_path):
    """A low-poly sphere of rough glass with smooth vertex normals on the floor under a lamp,
    the image's mean: a transmitting BSDF scatters light towards a side where the shading and
    geometric normals disagree, as the path tracer's does; BDPT's joins and light subpaths
    refused it while its MIS weights counted their strategies, 0.4 % dark (z -7, a review's
    measurement, 2026-11-30)."""
    low_poly_sphere_obj(tmp_path / "sphere.obj")
    scene = read_scene_dict({
        "camera": {"eye": [0, 2.2, 3.2], "look_at": [0, 0.4, 0], "up": [0, 1, 0], "vfov": 40},
        "environment": {"color": 0}, "render": {"max_depth": 6, "russian_roulette": "off"},
        "materials": {"floor": {"type": "diffuse", "rho_d": RHO}, "lamp": LAMP,
                      "glass": {"type": "roughdielectric", "alpha": 0.3}},
        "meshes": [{"vertices": [[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]], "faces": [[0, 3, 2, 1]],
                    "material": "floor"}, {"file": "sphere.obj", "material": "glass"}],
        "spheres": [{"center": [0.4, 2.0, -0.3], "radius": 0.3, "material": "lamp"}]}, "smooth-glass", folder=tmp_path)
    m = render_batches(backend, scene, "bdpt", 512, (32, 32), 8)[..., :3].mean(axis=(1, 2, 3))
    # the reference's variance is a seventh of BDPT's here: 16,384 samples widen the z's scale by 6 %
    ref, ref_v = _path_reference(backend, scene, 16384, (32, 32))
    z = (m.mean() - ref[..., :3].mean()) / np.sqrt(m.var(ddof=1) / len(m) + ref_v[..., :3].sum() / ref[..., :3].size ** 2)
    assert abs(z) < 4, (m.mean() / ref[..., :3].mean(), z)


def arch_obj(path, segments=4, radius=0.6, length=1.6):
    """An OBJ file of an open half-pipe, an arch over the z axis standing on y = 0, of few faces
    whose vertex normals are the cylinder's: light reaches it from behind a face's plane yet in
    front of its shading normal, and, the arch being open, nothing of it stands in the way."""
    angles = np.pi * np.arange(segments + 1) / segments
    points = [(radius * np.cos(a), radius * np.sin(a), z) for z in (-length / 2, length / 2) for a in angles]
    n = segments + 1
    lines = [f"v {x} {y} {z}" for x, y, z in points]
    lines += [f"vn {np.cos(a)} {np.sin(a)} 0" for _ in range(2) for a in angles]
    # counter-clockwise seen from outside
    lines += [f"f {i + 1}//{i + 1} {i + 2}//{i + 2} {n + i + 2}//{n + i + 2} {n + i + 1}//{n + i + 1}"
              for i in range(segments)]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("twosided", [False, True], ids=["one-sided", "two-sided"])
def test_bdpt_on_an_open_smooth_shaded_sheet_is_the_path_tracers(backend, tmp_path, twosided):
    """A low-poly arch of diffuse (or two-sided diffuse) with smooth vertex normals, lit by a
    lamp below its side, the image's mean: the path tracer carries light that arrives from
    behind a face's plane but in front of its shading normal, as Mitsuba 3 and pbrt-v4 do
    (kernels/integrator.cl), so BDPT's light subpaths must start such paths too."""
    arch_obj(tmp_path / "arch.obj")
    diffuse = {"type": "diffuse", "rho_d": RHO}
    scene = read_scene_dict({
        "camera": {"eye": [2.0, 0.2, 1.5], "look_at": [0.4, 0.1, 0], "up": [0, 1, 0], "vfov": 40},
        "environment": {"color": 0}, "render": {"max_depth": 4, "russian_roulette": "off"},
        "materials": {"arch": {"type": "twosided", "bsdf": diffuse} if twosided else diffuse, "lamp": LAMP},
        "meshes": [{"file": "arch.obj", "material": "arch"}],
        "spheres": [{"center": [0.8, -0.7, 0.3], "radius": 0.2, "material": "lamp"}]}, "arch", folder=tmp_path)
    m = render_batches(backend, scene, "bdpt", 512, (32, 32), 8)[..., :3].mean(axis=(1, 2, 3))
    # the reference's variance is a fiftieth of BDPT's here: 8,192 samples widen the z's scale by 3 %
    ref, ref_v = _path_reference(backend, scene, 8192, (32, 32))
    z = (m.mean() - ref[..., :3].mean()) / np.sqrt(m.var(ddof=1) / len(m) + ref_v[..., :3].sum() / ref[..., :3].size ** 2)
    assert abs(z) < 4, (m.mean() / ref[..., :3].mean(), z)


# -- BDPT against the path tracer on every scene file the tests hold --
# Each file as it is (its lights, delta ones included, textures, media, instances, cameras), at
# the small size of the NEE invariant over the same files (tests/scene_files.py), so that every
# file's BDPT program is one quick build: a Z-test of each 4x4-pixel block and of the whole
# image, per channel (tests/stats.py: z_test_of). The path tracer's error comes from its pixels'
# sample variances. BDPT's is the larger of two estimates: from its pixels' spread over the
# batches (its splats are not in the sums of squares), which leaves out that one light
# subpath's splats land in several pixels, and from the spread of the batches' own block and
# image means. A 10 % error in the light samples' (s = 1)
# contributions fails 56 of the 64 files (a review's measurement with 6 batches of 32 samples, 2026-11-30). A file whose camera
# has no importance (app/cameras/: Camera.importance) is refused by BDPT in one line.
SCENE_BLOCK = 4
SCENE_BATCHES = 12   # of 16 samples per pixel: the batches' spread is BDPT's error estimate where
                     # light subpaths' splats are heavy-tailed (lights at infinity through media),
                     # where 6 of 32 underestimated it (|z| 3.2-4.3 on media-sphere.xml, by chance)
PATH_TRACER_MISSES = {
    "mat_thindielectric.pbrt": "its sun, a delta light, through the thin glass sphere, a delta surface, onto the floor: "
                               "light the path tracer cannot sample, and pbrt-v4's cannot",
    "mat_dielectric_eta_below_one.pbrt": "its sun focused by the glass sphere onto the floor, likewise"}
"""Files where BDPT renders light that the path tracer cannot: there BDPT's image is the path
tracer's or brighter, block by block, and brighter in some block (with 4x the samples, which
puts that block's z near 9)."""


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_bdpt_converges_to_the_path_tracer_on_every_test_scene(backend, path):
    scene = load_scene(str(path)).with_settings(russian_roulette="off")
    if not type(scene.camera).importance:
        with pytest.raises(UserError, match="has no importance"):
            Renderer(backend, scene.with_settings(integrator="bdpt"), *SCENE_SIZE)
        return
    batches = render_batches(backend, scene, "bdpt", 64 if path.name in PATH_TRACER_MISSES else 16, SCENE_SIZE,
                             SCENE_BATCHES)
    assert np.all(np.isfinite(batches))
    means = blocks_and_image(batches, SCENE_BLOCK)
    bdpt_variance = np.maximum(variance_of_means(batches.var(0, ddof=1) / SCENE_BATCHES, SCENE_BLOCK),
                               means.var(0, ddof=1) / SCENE_BATCHES)
    path_mean, path_variance = _path_reference(backend, scene, 512, SCENE_SIZE)
    path_mean, path_variance = blocks_and_image(path_mean, SCENE_BLOCK), variance_of_means(path_variance, SCENE_BLOCK)
    if path.name in PATH_TRACER_MISSES:
        z = (means.mean(0) - path_mean) / np.sqrt(bdpt_variance + path_variance + 1e-30)
        assert z.min() > -5 and z.max() > 5, z
        return
    ok, p, threshold = z_test_of(means.mean(0), bdpt_variance + path_variance, path_mean)
    assert ok, (p, threshold)

def floor_radiance(scene, size, intensity, light, sub=4):
    """Each pixel's mean radiance of the floor under a point light of `intensity` at `light`,
    direct light only: RHO / pi * I cos / r^2 at the floor point each of sub x sub film points of
    the pixel sees."""
    w, h = size
    forward, right, up = scene.camera.basis(w / h)
    sx = (np.arange(w * sub) + 0.5) / (w * sub) * 2 - 1
    sy = 1 - (np.arange(h * sub) + 0.5) / (h * sub) * 2
    d = forward + sx[None, :, None] * right + sy[:, None, None] * up
    t = -scene.camera.eye[1] / d[..., 1]
    p = scene.camera.eye + t[..., None] * d
    v = np.asarray(light) - p
    r2 = (v * v).sum(-1)
    radiance = RHO / np.pi * (v[..., 1] / np.sqrt(r2) / r2)[..., None] * np.asarray(intensity)
    return radiance.reshape(h, sub, w, sub, 3).mean(axis=(1, 3))


@pytest.mark.parametrize("integrator", ["ptracer", "bdpt"])
def test_a_floor_under_a_point_light_has_the_closed_form(backend, integrator):
    """E = I cos / r^2, L = rho / pi E: light tracing alone reaches the floor from the light and
    the pinhole from the floor; BDPT adds the light sample (s = 1) and weighs the two."""
    light, intensity = [0.3, 1.2, -0.2], [3.0, 2.0, 1.0]
    camera = {"eye": [0, 3.0, 0.01], "look_at": [0, 0, 0], "up": [0, 0, -1], "vfov": 60}
    scene = floor_scene(lights=[{"type": "point", "position": light, "intensity": intensity}],
                        max_depth=2, camera=camera)
    size = (20, 20)
    m, v = render(backend, scene, integrator, 64, size)
    expected = floor_radiance(scene, size, intensity, light)
    ok, p, threshold = z_test(m, v, expected, block=2)
    assert ok, (p, threshold)
    assert abs(m.mean() / expected.mean() - 1) < 0.01


@pytest.mark.parametrize("integrator", ["ptracer", "bdpt"])
def test_a_floor_under_a_directional_light_has_the_closed_form(backend, integrator):
    """L = rho / pi E cos: light from infinity leaves a disk across the scene (kernels/lights.cl:
    leave_world_disk), and light tracing alone joins the floor it reaches to the pinhole; BDPT
    weighs that against sampling the light from the floor."""
    d = np.array([0.3, -1.0, 0.2]) / np.linalg.norm([0.3, -1.0, 0.2])
    irradiance = np.array([2.0, 1.0, 0.5])
    scene = read_scene_dict({
        "camera": {"eye": [0, 3.0, 0.01], "look_at": [0, 0, 0], "up": [0, 0, -1], "vfov": 40},
        "environment": {"color": 0}, "render": {"max_depth": 2, "russian_roulette": "off"},
        "materials": {"floor": {"type": "diffuse", "rho_d": RHO}},
        # a floor just wider than the view, so that most light subpaths from the disk over it are seen
        "meshes": [{"vertices": [[-1.5, 0, -1.5], [1.5, 0, -1.5], [1.5, 0, 1.5], [-1.5, 0, 1.5]], "faces": [[0, 3, 2, 1]],
                    "material": "floor"}],
        "lights": [{"type": "directional", "direction": d.tolist(), "irradiance": irradiance.tolist()}]}, "sun")
    m, v = render(backend, scene, integrator, 32, (16, 16))
    expected = RHO / np.pi * irradiance * -d[1]
    ok, p, threshold = z_test(m, v, np.broadcast_to(expected, m.shape), block=2)
    assert ok, (p, threshold)
    assert np.allclose(m.mean(axis=(0, 1)) / expected, 1, atol=0.01), m.mean(axis=(0, 1)) / expected


@pytest.mark.parametrize("material,albedo", [({"type": "diffuse", "rho_d": RHO}, RHO),
                                             ({"type": "diffusetransmission", "reflectance": 0.1,
                                               "transmittance": 0.8}, 0.9)])
def test_a_quad_under_a_constant_sky_has_the_closed_form(backend, material, albedo):
    """L = (R + T) Le on a lone quad that sees the sky on both sides: every strategy (the quad's
    path escaping, the sky sampled from the quad, light subpaths from the sky's disk joined to the
    pinhole) weighs in, on both sides of a transmitting quad (next-event estimation drawing the
    sky behind it too: kernels/lights/environment.cl, uniform_environment)."""
    scene = read_scene_dict({
        "camera": {"eye": [0, 3.0, 0.01], "look_at": [0, 0, 0], "up": [0, 0, -1], "vfov": 30},
        "environment": {"color": 0.5}, "render": {"max_depth": 2, "russian_roulette": "off"},
        "materials": {"quad": material},
        "meshes": [{"vertices": [[-1.5, 0, -1.5], [1.5, 0, -1.5], [1.5, 0, 1.5], [-1.5, 0, 1.5]], "faces": [[0, 3, 2, 1]],
                    "material": "quad"}]}, "sky")
    m, v = render(backend, scene, "bdpt", 32, (16, 16))
    ok, p, threshold = z_test(m, v, np.full_like(m, albedo * 0.5), block=2)
    assert ok, (p, threshold)
    assert abs(m.mean() / (albedo * 0.5) - 1) < 0.005, m.mean() / (albedo * 0.5)


def test_light_from_infinity_does_not_cross_an_unbounded_medium(backend):
    """A camera in fog that bounds nothing, under a sun and a sky: no light from infinity
    reaches the scene, by the path tracer's shadow rays or by BDPT's light subpaths."""
    scene = read_scene_dict({
        "camera": {"eye": [0, 0.5, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "vfov": 30, "medium": "fog"},
        "environment": {"color": 0.5}, "render": {"max_depth": 4, "russian_roulette": "off"},
        "materials": {"white": {"type": "diffuse", "rho_d": 0.6}},
        "media": {"fog": {"sigma_a": 0.02, "sigma_s": 0.1, "g": 0.0}},
        "spheres": [{"center": [0, 0, 0], "radius": 0.5, "material": "white"}],
        "lights": [{"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": [2, 2, 2]}]}, "fog")
    for integrator in ("path", "bdpt"):
        m, _ = render(backend, scene, integrator, 16, (12, 12), batches=2)
        assert np.all(m == 0.0), (integrator, m.max())


def test_a_furnace_of_emitting_walls_has_the_closed_form(backend):
    """A closed box whose inner walls emit Le and reflect diffusely with albedo rho: every path of
    depth D sees Le (1 + rho + ... + rho^(D-1)), whatever its strategy, and every pixel too."""
    rho, le, depth = 0.7, 0.5, 6
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    faces = []
    for quad in ([0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]):
        v = corners[quad]
        inward = np.dot(np.cross(v[1] - v[0], v[2] - v[0]), -v.mean(0)) > 0
        faces.append(quad if inward else quad[::-1])      # the front faces the inside
    scene = read_scene_dict({
        "camera": {"eye": [0.2, -0.1, 0.6], "look_at": [0, 0, -1], "up": [0, 1, 0], "vfov": 70},
        "environment": {"color": 0},
        "render": {"max_depth": depth, "russian_roulette": "off"},
        "materials": {"wall": {"type": "diffuse", "rho_d": rho, "Le": le}},
        "meshes": [{"vertices": corners.tolist(), "faces": faces, "material": "wall"}]}, "furnace")
    m, v = render(backend, scene, "bdpt", 8, (16, 16))
    expected = le * (1 - rho ** depth) / (1 - rho)
    ok, p, threshold = z_test(m, v, np.full_like(m, expected), block=2)
    assert ok, (p, threshold)
    assert abs(m.mean() / expected - 1) < 0.005, m.mean() / expected


MIS_SUMS = """
/* For pixel (x, y), a camera subpath that ends on an emitter or escapes to the environment (t
 * vertices, the last at infinity), taken as a path of n
 * = t vertices drawn by every strategy (s, n - s): the weights bdpt_mis_weight gives them, from
 * the densities the connections compute, summed over the strategies that can draw it (their
 * joined vertices not deltas). out: (sum, strategies, n, 0), or n = 0 where there is none. */
kernel void mis_sums(SCENE_KERNEL_ARGS, const RenderParams p, global float4 *out)
{
    SceneData sc = SCENE_DATA(p.num_spheres, p.layout);
    int x = get_global_id(0), y = get_global_id(1);
    int k = y * p.width + x;
    out[k] = (float4)(0.0f);
    Vertex cam[BDPT_CAMERA_VERTICES], lt[BDPT_LIGHT_VERTICES];
    int n = 0;
    /* the first of up to 64 samples whose camera subpath ends on an emitter */
    for (uint i = 0; i < 64 && n == 0; ++i) {
        Rng rng = make_rng(x, y, i, p.seed);
        CameraRay ray = sample_camera_ray(&p, x, y, &rng);
        cam[0].s.p = ray.o;
        cam[0].s.ng = (float3)(0.0f);
        cam[0].delta = 0;
        cam[0].pdf_fwd = 1.0f;
        cam[0].at_infinity = 0;
        cam[0].s.prim = -1;
#ifdef MEDIA
        cam[0].medium = p.camera_medium;
        cam[0].in_medium = 0;
#endif
        int rays = 0;
        n = extend_subpath(&sc, &p, cam, 1, BDPT_CAMERA_VERTICES, ray.o, ray.d, (float3)(1.0f),
                           pdf_camera_direction(&p, ray.d), NO_PRIM, medium_towards(&sc, &cam[0], ray.d), 0, &rng,
                           &rays);
        if (n < 3 || !cam[n - 1].emits
            || (!cam[n - 1].at_infinity && all(VERTEX_MATERIAL(&cam[n - 1])->emission.xyz == 0.0f)))
            n = 0;
    }
    if (n == 0)
        return;
    sum_mis_ratios(cam, n, 1, 0);
    /* the densities of the light's end of the path: drawn from the light, as a light subpath's */
    float4 from_light = densities_from_emitter(&sc, &p, &cam[n - 1], &cam[n - 2]);
    float sum = bdpt_mis_weight(lt, 0, cam, n, from_light, 0.0f, 0);
    int strategies = 1;
    cam[n - 1].pdf_rev = from_light.x;
    cam[n - 2].pdf_rev = from_light.y;
    int prim = cam[n - 1].s.prim, infinity = cam[n - 1].at_infinity;
    float3 to_light = -cam[n - 1].wo;    /* at infinity: the direction towards the environment */
    float3 normal = (float3)(0.0f);
    float origin = infinity ? from_light.x : emitter_at(&sc, prim, cam[n - 1].s.p, &normal);
    for (int s = 1; s < n; ++s) {
        int t = n - s;
        /* the light subpath: the camera subpath's last s vertices, reversed */
        for (int j = 0; j < s; ++j) {
            lt[j] = cam[n - 1 - j];
            lt[j].pdf_fwd = cam[n - 1 - j].pdf_rev;
            lt[j].pdf_rev = cam[n - 1 - j].pdf_fwd;
            if (j > 0)
                lt[j].wo = cam[n - j].at_infinity ? to_light : unit(cam[n - j].s.p - cam[n - 1 - j].s.p);
        }
        lt[0].pdf_fwd = origin;
        lt[0].s.ng = normal;
        lt[0].delta = 0;
        sum_mis_ratios(lt, s, 0, 0);
        const Vertex *qs = &lt[s - 1], *pt = &cam[t - 1];
        float4 rev;
        if (s == 1) {
            if (!pt->connectible)
                continue;
            const global Light *l = &sc.lights[0];
            for (int i = 0; i < p.num_lights; ++i)
                if (sc.lights[i].prim == prim)
                    l = &sc.lights[i];
            rev = infinity ? densities_to_infinity(&sc, &p, to_light, pt, &cam[t - 2])
                           : densities_to_light(&sc, &p, l, qs->s.p, normal, pt, &cam[t - 2]);
        } else if (!qs->connectible) {
            continue;
        } else if (t == 1) {
            rev = densities_to_camera(&sc, &p, qs, &lt[s - 2], p.eye.xyz);
        } else if (!pt->connectible) {
            continue;
        } else {
            rev = densities_between(&sc, qs, &lt[s - 2], pt, &cam[t - 2]);
        }
        sum += bdpt_mis_weight(lt, s, cam, t, rev, origin, 0);
        ++strategies;
    }
    out[k] = (float4)(sum, (float)strategies, (float)n, 0.0f);
}
"""


@pytest.mark.parametrize("make", [cbox, glass_scene, fog_glass_scene, sky_scene, normal_map_scene])
def test_the_mis_weights_of_a_path_sum_to_one(backend, make):
    """As pbrt-v4's BDPT tests check its weights: for each path a camera subpath draws to an
    emitter, or out to the environment, the weights of every strategy that could draw it,
    computed as the renders compute them, sum to 1 (the glass scene's paths through the sphere
    have delta vertices, whose strategies are left out)."""
    # at the scenes' depth 5, as test_converges_to_the_path_tracer renders them: its programs
    r = Renderer(backend, make().with_settings(integrator="bdpt"), 32, 32)
    features = replace(r.compiled.features(r.settings, r.camera), bdpt=5)
    program = build_program(backend.context, backend.device.device, MIS_SUMS, features=features).program
    out = np.zeros((32, 32, 4), np.float32)
    buf = cl.Buffer(backend.context, cl.mem_flags.WRITE_ONLY, out.nbytes)
    cl.Kernel(program, "mis_sums")(backend.queue, (32, 32), None, *r.scene_args(), r.params(1), buf)
    cl.enqueue_copy(backend.queue, out, buf)
    paths = out[..., 2] > 0
    lengths = set(out[paths][:, 2].astype(int))
    assert paths.sum() > 50 and len(lengths) >= 3, (paths.sum(), lengths)
    np.testing.assert_allclose(out[paths][:, 0], 1.0, rtol=2e-3, err_msg=str(out[paths][:20]))
    # every strategy of a path draws it in the Cornell box; through glass, some cannot
    all_strategies = out[paths][:, 1] == out[paths][:, 2]
    assert all_strategies.all() if make in (cbox, sky_scene, normal_map_scene) else not all_strategies.all()


PATH_WEIGHTS = """
/* Work-item k: a path of N vertices, x0 the lens and x(N-1) on a light, none a delta, where
 * pc[i] is the density of drawing x_i from the camera's side and pl[i] from the light's (the
 * densities dens[2 N k ...]); out[N k + t - 1]: bdpt_mis_weight of strategy (N - t, t), the
 * subpaths built as the renders build them. */
#define N 6
kernel void path_weights(global const float *dens, global float *out)
{
    int k = get_global_id(0);
    global const float *pc = dens + 2 * N * k, *pl = pc + N;
    for (int t = 1; t <= N; ++t) {
        int s = N - t;
        Vertex cam[N], lt[N];
        for (int i = 0; i < N; ++i) {
            cam[i].delta = lt[i].delta = 0;
            cam[i].pdf_fwd = pc[i];
            cam[i].pdf_rev = pl[i];
            lt[i].pdf_fwd = pl[N - 1 - i];
            lt[i].pdf_rev = pc[N - 1 - i];
        }
        if (s == 1)                /* the sampled light point is no light subpath's: its density is origin_pdf's */
            lt[0].pdf_fwd = 3.0f * pl[N - 1] + 0.5f;
        sum_mis_ratios(cam, t, 1, 0);
        sum_mis_ratios(lt, s, 0, 0);
        float4 rev = (float4)(t >= 1 ? pl[t - 1] : 0.0f, t >= 2 ? pl[t - 2] : 0.0f,
                              t < N ? pc[t] : 0.0f, t + 1 < N ? pc[t + 1] : 0.0f);
        out[N * k + t - 1] = bdpt_mis_weight(lt, s, cam, t, rev, pl[N - 1], 0);
    }
}
"""


def test_mis_weights_are_the_power_heuristics_at_extreme_densities(backend):
    """For a path of six vertices whose third and fourth lie a hair apart (each drawn from the
    other at an area density D), the weights of its six strategies against the power heuristic
    computed in float64 from the same densities: the same to 1e-5, summing to 1, up to D = 1e15;
    beyond, where the squared ratios pass a float, numbers in [0, 1] (an overflow's infinity
    times an underflow's 0 made NaN samples: Bitterli's coffee, 4 in 2.1 million)."""
    r = Renderer(backend, cbox().with_settings(integrator="bdpt"), 8, 8)
    features = replace(r.compiled.features(r.settings, r.camera), bdpt=5)
    program = build_program(backend.context, backend.device.device, PATH_WEIGHTS, features=features).program
    rng = np.random.default_rng(5)
    big = np.array([1.0, 1e4, 1e8, 1e10, 1e12, 1e15, 1e19, 1e25, 1e30, 1e35])
    n = len(big) * 8
    pc, pl = rng.uniform(0.3, 3.0, (2, n, 6))
    pc[:, 0] = 1.0                                      # a pinhole's lens
    d = np.repeat(big, 8)
    pc[:, 3] *= d                                       # x3 drawn from x2 a hair away,
    pl[:, 2] *= d / np.where(d > 1, rng.uniform(1e6, 1e9, n), 1.0)     # x2 from x3 at a grazing angle
    dens = np.concatenate([pc, pl], axis=1).astype(np.float32)
    out = np.zeros((n, 6), np.float32)
    mf = cl.mem_flags
    d_buf = cl.Buffer(backend.context, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=dens)
    o_buf = cl.Buffer(backend.context, mf.WRITE_ONLY, out.nbytes)
    cl.Kernel(program, "path_weights")(backend.queue, (n,), None, d_buf, o_buf)
    cl.enqueue_copy(backend.queue, out, o_buf)
    pc64, pl64 = dens[:, :6].astype(np.float64), dens[:, 6:].astype(np.float64)
    # strategy t draws x0 .. x(t-1) from the camera and the rest from the light
    logp = np.stack([np.log(pc64[:, :t]).sum(1) + np.log(pl64[:, t:]).sum(1) for t in range(1, 7)], axis=1)
    q = np.exp(2 * (logp - logp.max(axis=1, keepdims=True)))
    exact = q / q.sum(axis=1, keepdims=True)
    assert np.all(np.isfinite(out)) and out.min() >= 0 and out.max() <= 1, out[~np.isfinite(out).all(1)][:5]
    fits = d <= 1e15
    np.testing.assert_allclose(out[fits], exact[fits], atol=1e-5)
    np.testing.assert_allclose(out[fits].sum(axis=1), 1, atol=1e-5)


def test_bdpt_and_light_tracing_agree_on_a_point_light_in_fog(backend):
    """Next-event estimation towards a point inside a medium has an unbounded variance (the
    1 / r^2 of points of the fog near the light, integrated over the volume), so the path tracer
    is no reference here; light tracing, whose subpaths start at the light, converges, and BDPT
    must agree with it."""
    scene = fog_point_scene()
    m, v = render(backend, scene, "bdpt", 16, SIZE)
    ref, ref_v = render(backend, scene, "ptracer", 32, SIZE)
    ok, p, threshold = z_test(m, v, ref, ref_v, block=4)
    assert ok, (p, threshold)


@pytest.mark.parametrize("kind", [name for name, cls in CAMERAS.items() if not cls.importance])
def test_a_camera_without_importance_is_one_line_for_bdpt(backend, kind):
    """A camera type whose kernel cannot join light subpaths to its lens (app/cameras/:
    Camera.importance) is refused in one line, not rendered wrong."""
    scene = cbox()
    scene = replace(scene, camera=scene.camera.as_type(kind)).with_settings(integrator="bdpt")
    with pytest.raises(UserError, match=f"^{ROOT / 'tests/scenes/cbox.xml'}: integrator bdpt: the {kind} camera "
                                        "has no importance"):
        Renderer(backend, scene, 8, 8)


def test_every_light_type_starts_light_subpaths():
    """BDPT's MIS weights count light subpaths from every light: next-event estimation towards a
    type without them would be weighed against strategies that never draw (goniometric and
    projection lights rendered 96 % dark so, before they had them)."""
    from pathtrace.lights.registry import EMITTERS, LIGHTS
    assert set(LIGHTS) == set(EMITTERS)


def test_the_path_tracers_program_compiles_nothing_of_bdpt(backend):
    from pathtrace.device.opencl import kernel_source
    scene = cbox()
    r = Renderer(backend, scene, 8, 8)
    features = r.compiled.features(r.settings, r.camera)
    assert features.bdpt == 0 and not any(d.startswith("BDPT") for d in features.defines())
    source = kernel_source(features=features)
    emitters = "return emit_area_light(sc, p, l, u, e);"     # the generated dispatch of light subpaths
    assert '"bdpt.cl"' not in source and emitters not in source and "render_bdpt" not in source
    assert source == kernel_source(features=replace(features, bdpt=0))
    bidirectional = kernel_source(features=replace(features, bdpt=5))
    assert "render_bdpt" in bidirectional and emitters in bidirectional


# --- choosing the integrator: the scene file, the command line, the Python API -------------------

@pytest.mark.parametrize("kind,integrator,radius,note", [
    ("bdpt", "bdpt", 0, None), ("path", "path", 0, None),
    ('sppm" "float radius" [ 0.05 ]', "bdpt", 0.05, "renders sppm with bdpt and caustic photons of radius 0.05"),
    ('sppm"', "bdpt", 1.0, "renders sppm with bdpt and caustic photons of radius 1"),     # pbrt-v4's default
    ("mlt", "bdpt", 0, "renders mlt with bdpt, the nearest method"), ("lightpath", "bdpt", 0, "renders lightpath with bdpt")])
def test_a_pbrt_file_chooses_its_integrator(tmp_path, capsys, kind, integrator, radius, note):
    path = tmp_path / "s.pbrt"
    kind = kind if kind.startswith("sppm") else kind + '"'
    path.write_text(f'Integrator "{kind}\nWorldBegin\n'
                    'Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1 ] "integer indices" [ 0 2 1 ]\n')
    settings = load_scene(str(path)).settings
    assert settings.integrator == integrator and settings.photon_radius == pytest.approx(radius)
    err = capsys.readouterr().err
    assert (note in err and len(err.strip().splitlines()) == 1) if note else note is None


@pytest.mark.parametrize("radius", ["0", "-1", "1e400"])
def test_a_pbrt_sppm_radius_out_of_range_is_one_line(tmp_path, radius):
    path = tmp_path / "s.pbrt"
    path.write_text(f'Integrator "sppm" "float radius" [ {radius} ]\nWorldBegin\n')
    with pytest.raises(UserError, match="'radius': (must be in|1e400 is not finite)"):
        load_scene(str(path))


@pytest.mark.parametrize("kind", ["bdpt", "ptracer"])
def test_a_mitsuba_file_chooses_its_integrator(tmp_path, kind):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0"><integrator type="{kind}"/>'
                    '<shape type="sphere"><float name="radius" value="1"/></shape></scene>')
    assert load_scene(str(path)).settings.integrator == kind


def test_a_toml_file_chooses_its_integrator_and_keeps_it(tmp_path):
    from pathtrace.scene.toml_writer import scene_toml
    path = tmp_path / "s.toml"
    sphere = '[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = { type = "diffuse", rho_d = 0.5 }\n'
    path.write_text('[render]\nintegrator = "bdpt"\n' + sphere)
    scene = load_scene(str(path))
    assert scene.settings.integrator == "bdpt"
    (tmp_path / "t.toml").write_text(scene_toml(scene, tmp_path / "t.toml"))
    assert load_scene(str(tmp_path / "t.toml")).settings.integrator == "bdpt"
    path.write_text('[render]\nintegrator = "mlt"\n' + sphere)
    with pytest.raises(UserError, match=r"render.integrator: must be one of path, bdpt, ptracer, got 'mlt'$"):
        load_scene(str(path))
    path.write_text('[render]\nintegrator = "bdtp"\n' + sphere)
    with pytest.raises(UserError, match=r"render.integrator: must be one of path, bdpt, ptracer, got 'bdtp'; "
                                        r"did you mean bdpt\?$"):
        load_scene(str(path))


def test_the_api_renders_with_the_integrator_it_is_given(backend):
    from pathtrace import api
    scene = cbox()
    image = api.render(scene, spp=4, size=(12, 12), device="cpu", integrator="ptracer")
    assert image.shape == (12, 12, 3) and np.isfinite(image).all() and image.mean() > 0
    with pytest.raises(UserError, match="integrator: give one of path, bdpt, ptracer"):
        api.render(scene, spp=1, size=(4, 4), device="cpu", integrator="sppm")


def test_bdpt_gives_the_denoiser_the_camera_paths_first_vertex(backend):
    """Light tracing's splats have no albedo or normal of their own: BDPT's AOVs are the camera
    ray's first hit, as the path tracer's are, and the denoiser smooths BDPT's image with them."""
    from pathtrace import api
    out = {integrator: api.render(cbox(), spp=4, size=(64, 64), device="cpu", integrator=integrator, seed=3,
                                  aovs=("albedo", "normal"))
           for integrator in ("path", "bdpt")}
    for aov in ("albedo", "normal"):
        np.testing.assert_allclose(out["bdpt"][aov], out["path"][aov], atol=0.05)
    image = out["bdpt"]["image"]
    denoised = api.denoise(image, out["bdpt"]["albedo"], out["bdpt"]["normal"])
    converged = api.render(cbox(), spp=512, size=(64, 64), device="cpu", seed=5)
    error = lambda x: np.abs(x - converged).mean()     # noqa: E731
    assert np.isfinite(denoised).all() and error(denoised) < 0.7 * error(image), (error(denoised), error(image))


def test_the_command_line_renders_with_bdpt_and_refuses_what_it_cannot_in_one_line(tmp_path):
    out = tmp_path / "a.exr"
    r = in_process("render", "tests/scenes/cbox.xml", "--integrator", "bdpt", "--size", "12x12", "--spp", "2",
                  "--max-depth", "5", "-o", out, "-q")     # the depth of cbox()'s program
    assert r.returncode == 0 and out.exists(), r.stderr
    r = in_process("render", "tests/scenes/media-fog.xml", "--integrator", "bdpt", "--filter", "box", "--size", "8x8",
                  "--spp", "1", "--max-depth", "5", "-o", tmp_path / "fog.exr", "-q")
    assert r.returncode == 0 and (tmp_path / "fog.exr").exists(), r.stderr
    r = in_process("render", "tests/scenes/envmap-spheres.xml", "--integrator", "ptracer", "--size", "8x8",
                  "--spp", "1", "-o", tmp_path / "b.exr", "-q")
    lines = [line for line in r.stderr.splitlines() if not line.startswith("device: ")]
    assert r.returncode != 0 and len(lines) == 1 and "not reached by light tracing" in lines[0], r.stderr
    assert not (tmp_path / "b.exr").exists()
    # the photons are BDPT's: asked of the path tracer, one line rather than a setting it never reads
    r = in_process("render", "cornell-box", "--photon-radius", "0.1", "--size", "8x8", "--spp", "1",
                   "-o", tmp_path / "c.exr", "-q")
    assert r.returncode != 0 and not (tmp_path / "c.exr").exists()
    assert r.stderr.strip().splitlines()[-1].endswith("renders with path: give --integrator bdpt too"), r.stderr


# --- splats add up wherever the samples are drawn -------------------------------------------------

@pytest.mark.parametrize("make", [cbox, pool_scene])
def test_splats_of_samples_split_by_index_and_rows_add_up(backend, make):
    """Samples 0-12 added as 4-7, 0-3, 8-11 in two bands of rows and 12 in two bands one after
    the other (whose second band gathers the photons its first traced) give the image of one
    launch of 13: each launch's splats land in the whole image, whatever rows it renders, and a
    sample's caustic photons and their radius are the sample's, whoever draws it."""
    scene = make().with_settings(integrator="bdpt")
    whole = Renderer(backend, scene, 16, 16)
    whole.add_samples(13)
    parts = Renderer(backend, scene, 16, 16)
    parts.add_samples(4, 4)
    parts.add_samples(4, 0)
    parts.add_samples(4, 8, rows=(0, 7))
    parts.add_samples(4, 8, rows=(7, 16))
    parts.add_samples(1, 12, rows=(0, 5))
    parts.add_samples(1, 12, rows=(5, 16))
    assert parts.samples == 13
    # the splats' atomic additions come in any order: float rounding apart
    np.testing.assert_allclose(parts.mean(), whole.mean(), rtol=2e-5, atol=1e-7)


def test_two_devices_splat_the_one_device_image(backend):
    """One device split twice (two contexts and queues): the merged sums of a BDPT render equal
    a one-device render of the same samples (pathtrace.rendering.multidevice), splats included."""
    from pathtrace.device.opencl import open_device
    from pathtrace.rendering.multidevice import DeviceGroup
    scene = cbox().with_settings(integrator="bdpt", width=16, height=16)
    second = open_device(backend.device)
    group = DeviceGroup([backend, second], scene)
    group.render(24, launch_seconds=0.01)
    single = Renderer(backend, scene)
    single.add_samples(24)
    assert group.samples == 24
    np.testing.assert_allclose(group.mean(), single.mean(), rtol=2e-5, atol=1e-7)


def test_the_photon_radius_shrinks_by_knaus_and_zwickers_rule():
    """The closed form of the radius before each sample is the recurrence r_{i+1}^2 = r_i^2
    (i + alpha) / (i + 1) from r_1, and it tends to 0 (the photons' bias vanishes)."""
    from pathtrace.rendering.photons import ALPHA, photon_radius
    r2 = 0.3 ** 2
    for i in range(1, 200):
        assert photon_radius(0.3, i - 1) == pytest.approx(np.sqrt(r2), rel=1e-9)
        r2 *= (i + ALPHA) / (i + 1)
    assert photon_radius(0.3, 10 ** 6) < 0.3 * 0.2


@pytest.mark.parametrize("name", ["media-fog", "media-sphere", "media-glass"])
def test_bdpt_in_media_matches_mitsuba(backend, name):
    """BDPT's image of the medium scenes against Mitsuba 3's volpath references (tests/references,
    scripts/make_references.py): an independent renderer, not pathtrace's path tracer. BDPT's
    variance comes from its renders' spread (the splats are not in a pixel's sums of squares)."""
    ref = np.load(ROOT / "tests/references" / f"{name}.npz")
    h, w, _ = ref["mean"].shape
    scene = load_scene(str(ROOT / "tests/scenes" / f"{name}.xml")).with_settings(
        max_depth=int(ref["max_depth"]), russian_roulette="off")
    m, v = render(backend, scene, "bdpt", 48, (w, h))
    ok, p, threshold = z_test(m, v, ref["mean"].astype(np.float64), ref["var_of_mean"].astype(np.float64), block=4)
    assert ok, (p, threshold)


def test_the_depth_warning_names_the_integrator_and_the_settings(capsys, monkeypatch):
    """A depth beyond what a BDPT program holds is said once per value and integrator, naming
    the integrator (light tracing's warning had said bdpt) and the render's settings, which a
    command line sets as well as a scene."""
    from pathtrace.rendering import bdpt
    monkeypatch.setattr(bdpt, "_warned", set())
    assert bdpt.depth(20, "ptracer") == bdpt.MAX_DEPTH and bdpt.depth(20, "ptracer") == bdpt.MAX_DEPTH
    assert bdpt.depth(0, "bdpt") == bdpt.MAX_DEPTH and bdpt.depth(3, "bdpt") == 3
    assert capsys.readouterr().err.splitlines() == [
        f"pathtrace: warning: ptracer: paths end at depth {bdpt.MAX_DEPTH} (the render's settings ask for max_depth 20)",
        f"pathtrace: warning: bdpt: paths end at depth {bdpt.MAX_DEPTH} (the render's settings ask for no limit)"]
