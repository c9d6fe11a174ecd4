"""Writes a glass of water on a table under a small lamp (#58's scene of its own): FOLDER/
glass-of-water.xml, Mitsuba 3 XML that pathtrace reads too, with glass.ply and water.ply. The
lamp's light, refracted by the glass and the water, focuses into a caustic on the table, which
the camera sees directly: paths the path tracer finds only where a bounce off the table happens
to reach the lamp through the glass, and BDPT by light tracing. The water stands a hair inside
the glass (an air gap, the usual approximation of a glass-water interface). python
docs/notes/studies/glass_of_water.py FOLDER"""
import sys
from pathlib import Path

import numpy as np

SEGMENTS = 160


def revolve(profile, normals, segments=SEGMENTS):
    """The surface of revolution about y of a polyline of (r, y) points, each of its segments a
    band of quads with its own vertices (sharp corners between bands), smooth around the axis:
    normals holds each segment's (r, y) outward normal at its two ends."""
    phi = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    c, s = np.cos(phi), np.sin(phi)
    vertices, vertex_normals, faces = [], [], []
    for (a, b), (na, nb) in zip(zip(profile[:-1], profile[1:]), normals):
        base = sum(len(v) for v in vertices)
        ring = lambda p: np.stack([p[0] * c, np.full(segments, p[1]), p[0] * s], -1)
        ring_n = lambda n: np.stack([n[0] * c, np.full(segments, n[1]), n[0] * s], -1)
        vertices += [ring(a), ring(b)]
        vertex_normals += [ring_n(na), ring_n(nb)]
        for k in range(segments):
            k1 = (k + 1) % segments
            i0, i1, j0, j1 = base + k, base + k1, base + segments + k, base + segments + k1
            # a band that starts or ends on the axis is a fan: one triangle per quad
            faces += [[i0, j0, j1]] if a[0] == 0 else [[i0, j0, i1]] if b[0] == 0 else [[i0, j0, j1], [i0, j1, i1]]
    v, n, f = np.concatenate(vertices), np.concatenate(vertex_normals), np.array(faces)
    # wind each triangle so that its front faces the way its normals do
    e = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    flip = (e * n[f].sum(1)).sum(1) < 0
    f[flip] = f[flip][:, ::-1]
    return v, n, f


def write_ply(path, v, n, f):
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\n"
              f"property float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face {len(f)}\n"
              "property list uchar int vertex_indices\nend_header\n")
    vertex = np.concatenate([v, n], 1).astype("<f4")
    face = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", 3)])
    face["n"], face["i"] = 3, f
    Path(path).write_bytes(header.encode() + vertex.tobytes() + face.tobytes())


def main(folder: Path):
    folder.mkdir(parents=True, exist_ok=True)
    # the glass stands a hair above the table: a face in the table's plane would leave which of
    # the two a ray meets to each renderer's rounding
    r_out, r_in, foot, base, top = 0.40, 0.36, 0.001, 0.08, 1.0
    glass = revolve([(0.0, foot), (r_out, foot), (r_out, top), (r_in, top), (r_in, base), (0.0, base)],
                    [((0, -1), (0, -1)), ((1, 0), (1, 0)), ((0, 1), (0, 1)), ((-1, 0), (-1, 0)), ((0, 1), (0, 1))])
    r_w, bottom, level = r_in - 0.002, base + 0.002, 0.72
    water = revolve([(0.0, bottom), (r_w, bottom), (r_w, level), (0.0, level)],
                    [((0, -1), (0, -1)), ((1, 0), (1, 0)), ((0, 1), (0, 1))])
    write_ply(folder / "glass.ply", *glass)
    write_ply(folder / "water.ply", *water)
    (folder / "glass-of-water.xml").write_text("""<?xml version="1.0" encoding="utf-8"?>
<!-- A glass of water on a table under a small lamp (docs/notes/studies/glass_of_water.py). -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="width" value="256"/>
    <default name="height" value="192"/>
    <integrator type="path">
        <integer name="max_depth" value="10"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world">
            <lookat origin="0.2, 1.7, 3.4" target="-0.25, 0.25, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$width"/>
            <integer name="height" value="$height"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="constant">
        <rgb name="radiance" value="0.02, 0.022, 0.025"/>
    </emitter>
    <shape type="sphere">
        <point name="center" x="1.1" y="1.5" z="-0.5"/>
        <float name="radius" value="0.015"/>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0, 0, 0"/>
        </bsdf>
        <emitter type="area">
            <rgb name="radiance" value="10000, 8900, 7200"/>
        </emitter>
    </shape>
""" + rectangle('<rotate x="1" angle="-90"/>', "0.62, 0.5, 0.38")      # the table
      + rectangle('<translate z="-2"/>', "0.7, 0.7, 0.7")                # the wall behind
      + dielectric("glass.ply", 1.5) + dielectric("water.ply", 1.33) + "</scene>\n")


def rectangle(placement: str, reflectance: str) -> str:
    """A diffuse 6 x 6 square, placed by `placement` after its scaling."""
    return f"""    <shape type="rectangle">
        <transform name="to_world">
            <scale value="3"/>
            {placement}
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="{reflectance}"/>
        </bsdf>
    </shape>
"""


def dielectric(ply: str, ior: float) -> str:
    return f"""    <shape type="ply">
        <string name="filename" value="{ply}"/>
        <bsdf type="dielectric">
            <float name="int_ior" value="{ior}"/>
        </bsdf>
    </shape>
"""


if __name__ == "__main__":
    main(Path(sys.argv[1]))
