"""Regenerates tests/references/*.npz: reference images of scenes (spheres and triangle meshes,
with the materials Mitsuba has too) rendered by an independent renderer, Mitsuba 3
(`pip install mitsuba plyfile`), in its scalar_rgb variant (its LLVM variant failed to compile
its kernels with Debian 12's LLVM 15 on the machine this ran on).

Each reference holds the mean of K independent renders and the variance of that mean (from the
spread of the K renders), at a small size. Both renderers see the same scene: shapes with the
same materials (Mitsuba's names and parameters, which pathtrace's share), sphere area lights, a
constant or HDR environment, a pinhole camera with a box pixel filter, and the comparison mode
of the benchmark specification (max_depth 8, no Russian roulette before it).

    python scripts/make_references.py [scene ...]
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

from pathtrace.scene import load_scene

OUT = Path(__file__).resolve().parent.parent / "tests" / "references"
SCENES = {  # name: (width, height, spp per render, renders)
    "simple-diffuse": (64, 36, 1024, 16),
    "spheres8k-diffuse": (64, 36, 512, 16),
    "cornell-box": (48, 48, 1024, 16),
    "material-spheres": (96, 36, 1024, 16),
    "material-spheres-hdr": (96, 36, 1024, 16),
    # Mitsuba XML scenes of tests/scenes/, which Mitsuba loads itself (their size is theirs)
    "cbox": (None, None, 1024, 16),
    "envmap-spheres": (None, None, 1024, 16),
    "envmap-tilted": (None, None, 1024, 16),
    "meshes": (None, None, 1024, 16),
    "meshes-smaller": (None, None, 1024, 16),
    "meshes-larger": (None, None, 1024, 16),
    "textures": (None, None, 1024, 16),
    "masks": (None, None, 1024, 16),
    "normal-maps": (None, None, 1024, 16),
    "lights": (None, None, 1024, 16),
    "thinlens": (None, None, 1024, 16),
    "beckmann": (None, None, 1024, 16),
    "roughdielectric": (None, None, 1024, 16),
    "roughplastic": (None, None, 1024, 16),
    "metals": (None, None, 1024, 16),
    "media-sphere": (None, None, 1024, 16),
    "media-glass": (None, None, 1024, 16),
    "media-fog": (None, None, 1024, 16),
    "anisotropic": (None, None, 1024, 16),
    "blend": (None, None, 1024, 16),
    "equal-area": (None, None, 1024, 16),
    "principled": (None, None, 1024, 16),
    "instances": (None, None, 1024, 16),
    "glass-mesh": (None, None, 1024, 16),
    "open-sheet": (None, None, 1024, 16),
    "serialized": (None, None, 1024, 16),
}
XML_SCENES = OUT.parent / "scenes"
MAX_DEPTH = 8


def mitsuba_scene(mi, scene, width, height, spp):
    rgb = lambda v: {"type": "rgb", "value": [float(x) for x in v]}  # noqa: E731
    cam = scene.camera
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": MAX_DEPTH, "rr_depth": 1000},
        "sensor": {
            "type": "perspective", "fov": float(cam.vfov), "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(origin=cam.eye.tolist(), target=cam.look_at.tolist(),
                                                       up=cam.up.tolist()),
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp},
        },
    }
    environment = scene.environment
    if environment.image.shape[:2] != (1, 1):
        # Mitsuba's map puts u = 0 at -z where pathtrace puts u = 1/2 (kernels/environment.cl):
        # half a turn about +y
        if environment.rotation:
            raise SystemExit(f"{scene.name}: rotated maps have no reference yet")
        path = Path(tempfile.mkdtemp()) / "environment.exr"
        mi.Bitmap(np.ascontiguousarray(environment.image[..., :3], np.float32)).write(str(path))
        d["environment"] = {"type": "envmap", "filename": str(path), "scale": float(environment.intensity),
                            "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], 180.0)}
    elif np.any(environment.image[0, 0] * environment.intensity > 0):
        d["environment"] = {"type": "constant", "radiance": rgb(environment.image[0, 0] * environment.intensity)}
    table = scene.materials

    def shape_props(row):
        m = table.get(row)
        props = {"bsdf": mitsuba_bsdf(m, rgb, scene.name)}
        if np.any(m.emission > 0):
            props["emitter"] = {"type": "area", "radiance": rgb(m.emission)}
        return props

    for i, s in enumerate(scene.spheres):
        d[f"sphere{i}"] = {"type": "sphere", "center": s[:3].tolist(), "radius": float(s[3]),
                           **shape_props(int(scene.sphere_material[i]))}
    folder = Path(tempfile.mkdtemp())
    for i, mesh in enumerate(scene.meshes):
        path = folder / f"mesh{i}.ply"
        write_ply(path, mesh.vertices, mesh.faces)
        d[f"mesh{i}"] = {"type": "ply", "filename": str(path), "face_normals": mesh.normals is None,
                         **shape_props(mesh.material)}
    return mi.load_dict(d)


def mitsuba_bsdf(m, rgb, scene_name):
    """The Mitsuba BSDF of a material; the parameters share Mitsuba's names and meaning."""
    p = {k: (rgb(np.broadcast_to(v, 3)) if np.ndim(v) else float(v)) for k, v in m.params.items()}
    if m.type == "black":
        bsdf = {"type": "diffuse", "reflectance": rgb((0, 0, 0))}
    elif m.type == "diffuse":
        bsdf = {"type": "diffuse", "reflectance": p["rho_d"]}
    elif m.type == "roughconductor":
        bsdf = {"type": "roughconductor", "distribution": "ggx", **p}
    elif m.type in ("plastic", "roughplastic"):
        bsdf = {"type": m.type, **p, "nonlinear": bool(m.params["nonlinear"])}
        if m.type == "roughplastic":
            bsdf["distribution"] = "ggx"
    elif m.type in ("conductor", "dielectric", "thindielectric"):
        bsdf = {"type": m.type, **p}
    else:
        raise SystemExit(f"{scene_name}: Mitsuba has no {m.type} material")
    return {"type": "twosided", "bsdf": bsdf} if m.twosided else bsdf


def write_ply(path, vertices, faces):
    from plyfile import PlyData, PlyElement
    v = np.array([tuple(p) for p in vertices], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    f = np.array([(tuple(t),) for t in faces], dtype=[("vertex_indices", "i4", (3,))])
    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]).write(str(path))


def main(names):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    OUT.mkdir(parents=True, exist_ok=True)
    for name in names or SCENES:
        width, height, spp, runs = SCENES[name]
        xml = XML_SCENES / f"{name}.xml"
        if xml.exists():
            m = mi.load_file(str(xml), spp=spp)
            width, height = m.sensors()[0].film().size()
        else:
            m = mitsuba_scene(mi, load_scene(name), width, height, spp)
        images = np.stack([np.array(mi.render(m, seed=k), np.float64)[..., :3] for k in range(runs)])
        mean = images.mean(axis=0)
        var_of_mean = images.var(axis=0, ddof=1) / runs
        np.savez_compressed(OUT / f"{name}.npz", mean=mean.astype(np.float32),
                            var_of_mean=var_of_mean.astype(np.float32),
                            spp=spp * runs, max_depth=MAX_DEPTH, renderer=f"Mitsuba {mi.__version__} {mi.variant()}")
        print(f"{name}: {width}x{height}, {spp * runs} spp, mean {mean.mean(axis=(0, 1))}")


if __name__ == "__main__":
    main(sys.argv[1:])
