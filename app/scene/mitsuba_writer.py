"""A scene written as Mitsuba 3 XML: the twin that `pathtrace bench --mitsuba` has Mitsuba render,
so that both renderers time the same work. The subset is what the benchmark scenes hold:
spheres and triangle meshes (written beside the XML as binary PLY files, with their normals and
uvs), diffuse and black materials (two-sided where pathtrace's are), area emitters, a constant
environment, a perspective pinhole camera with a box filter, and the path integrator at the
scene's max depth. Anything else (other BSDFs, textures, maps, lights, lenses, media, instances)
is refused in one line: a twin that differed would time other work."""

from pathlib import Path

import numpy as np

from pathtrace.errors import UserError
from pathtrace.scene.description import Scene


def ply_bytes(points, faces, normals=None, uvs=None) -> bytes:
    """A binary little-endian PLY file of float32 vertices (with normals, with uvs as u, v) and
    int32 triangles, as exporters write them."""
    names = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else []) + (["u", "v"] if uvs is not None else [])
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(points)}"]
    header += [f"property float {n}" for n in names]
    header += [f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    columns = [c for c in (points, normals, uvs) if c is not None]
    records = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    records["n"], records["i"] = 3, faces
    return ("\n".join(header) + "\n").encode() + np.concatenate(columns, 1).astype("<f4").tobytes() + records.tobytes()


def _rgb(value) -> str:
    return ", ".join(f"{float(x):.9g}" for x in np.broadcast_to(np.asarray(value, np.float64), 3))


def _vector(value) -> str:
    return ", ".join(f"{float(x):.9g}" for x in value)


def _material(scene: Scene, row: int) -> str:
    """The BSDF and area emitter of a shape of material `row`."""
    m = scene.materials.get(row)
    name = scene.materials.name_of(row) or f"#{row}"
    if m.type not in ("diffuse", "black") or any(not isinstance(v, (int, float, np.ndarray, np.number))
                                                 for v in m.params.values()):
        raise UserError(f"{scene.source or scene.name}: material {name}: only diffuse and black materials "
                        f"without textures are written as Mitsuba XML ({m.type})")
    reflectance = m.params["rho_d"] if m.type == "diffuse" else 0.0
    bsdf = f'<bsdf type="diffuse"><rgb name="reflectance" value="{_rgb(reflectance)}"/></bsdf>'
    if m.twosided:
        bsdf = f'<bsdf type="twosided">{bsdf}</bsdf>'
    if np.any(m.emission > 0) and m.emits_back:
        raise UserError(f"{scene.source or scene.name}: material {name}: Mitsuba 3's area emitters have one "
                        "side; a material emitting from both is not written as Mitsuba XML")
    if np.any(m.emission > 0):
        bsdf += f'<emitter type="area"><rgb name="radiance" value="{_rgb(m.emission)}"/></emitter>'
    return bsdf


def write_mitsuba(scene: Scene, path: Path) -> Path:
    """Writes `scene` as Mitsuba 3 XML at `path`, its meshes as PLY files beside it; returns path."""
    path = Path(path)
    where = scene.source or scene.name
    cam = scene.camera
    if cam.kernel != "perspective" or cam.mirrored:
        raise UserError(f"{where}: only pinhole perspective cameras (right-handed) are written as Mitsuba XML")
    env = scene.environment
    if env.image.shape[:2] != (1, 1):
        raise UserError(f"{where}: environment maps are not written as Mitsuba XML")
    if scene.lights or scene.instances is not None or scene.media or scene.shapes:
        raise UserError(f"{where}: lights other than emitting shapes, instances, media and analytic shapes are not "
                        f"written as Mitsuba XML")
    s = scene.settings
    radiance = env.image[0, 0, :3] * env.intensity
    shapes = [f'<shape type="sphere"><point name="center" value="{_vector(c[:3])}"/>'
              f'<float name="radius" value="{float(c[3]):.9g}"/>{_material(scene, int(m))}</shape>'
              for c, m in zip(scene.spheres, scene.sphere_material)]
    for i, mesh in enumerate(scene.meshes):
        ply = path.with_name(f"{path.stem}-mesh{i}.ply")
        ply.write_bytes(ply_bytes(mesh.vertices, mesh.faces, mesh.normals, mesh.uvs))
        flat = "" if mesh.normals is not None else '<boolean name="face_normals" value="true"/>'
        shapes.append(f'<shape type="ply"><string name="filename" value="{ply.name}"/>{flat}'
                      f'{_material(scene, mesh.material)}</shape>')
    path.write_text(scene_xml((s.width, s.height), cam.eye, cam.look_at, cam.up, cam.vfov, s.spp,
                              s.max_depth if s.max_depth else -1, radiance if np.any(radiance > 0) else None, shapes))
    return path


def scene_xml(size, eye, target, up, vfov: float, spp: int, max_depth: int, sky, shapes) -> str:
    """A Mitsuba 3 scene file: the path integrator at max_depth (-1: no limit), a perspective
    pinhole camera at eye looking at target (vfov degrees, vertically) with a film of `size` and
    a box filter, `spp` independent samples, a constant sky of radiance `sky` (None: none), and
    `shapes` (their XML elements)."""
    lines = ['<scene version="3.0.0">',
             f'<integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>',
             f'<sensor type="perspective"><float name="fov" value="{float(vfov):.9g}"/>'
             '<string name="fov_axis" value="y"/><transform name="to_world">'
             f'<lookat origin="{_vector(eye)}" target="{_vector(target)}" up="{_vector(up)}"/></transform>'
             f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>'
             f'<film type="hdrfilm"><integer name="width" value="{size[0]}"/><integer name="height" value="{size[1]}"/>'
             '<rfilter type="box"/><string name="pixel_format" value="rgb"/></film></sensor>']
    if sky is not None:
        lines.append(f'<emitter type="constant"><rgb name="radiance" value="{_rgb(sky)}"/></emitter>')
    return "\n".join(lines + list(shapes) + ["</scene>", ""])
