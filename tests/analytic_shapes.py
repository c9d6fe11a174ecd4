"""What the tests of pbrt-v4's quadrics (tests/test_disk.py, tests/test_cylinder.py) share: rays
at object points of a shape checked against pbrt-v4's parameterisation, and a pbrt-v4 file's
emitting shape."""

import numpy as np

from pathtrace.scene import load_scene, transform
from pathtrace.shapes import Shape
from tests.test_shapes import one_shape_scene, shape_hits

PBRT_EMITTER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 45
Film "rgb" "integer xresolution" 16 "integer yresolution" 16 "string filename" "x.exr"
WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [1 1 1] "float power" 10
Material "diffuse"
{lines}
AttributeEnd
"""


def pbrt_scene(tmp_path, lines: str):
    """The scene of a pbrt-v4 file of `lines` after a camera on the z axis, 5 units out."""
    path = tmp_path / "s.pbrt"
    path.write_text('LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\n' + lines + "\n")
    return load_scene(str(path))


def moved(m, points):
    """(n, 3) points moved by the (4, 4) transform m."""
    return points @ m[:3, :3].T + m[:3, 3]


def placed_quadric(kind, params, uniform, flip, rng, n):
    """(scene, m, phi): a one-shape scene of `kind` (params: radius, z_min, z_max, phi_max) under
    m, which moves, turns and scales it (evenly where `uniform`), and n angles in (0, phi_max)."""
    m = transform.translation([0.3, -0.2, 1.0]) @ transform.rotation([1, 2, 0], 50) \
        @ transform.scaling([1.2] * 3 if uniform else [0.7, 1.6, 1.1])
    scene = one_shape_scene(Shape(kind[0], kind, params, m, 0, flip=flip))
    return scene, m, rng.uniform(0.001, 0.999, n) * params[3]


def hits_as_pbrt(kernels, scene, m, start, local, uv, phi_max, atol, dpdu_atol):
    """The hits of rays from object points `start` towards object points `local` on the shape of
    `scene` under m (tests/test_shapes.py shape_hits), checked to meet it at `local` with texture
    coordinates `uv` and pbrt-v4's dp/du = phi_max (-y, x, 0) moved to the world."""
    h = shape_hits(kernels, scene, moved(m, start), moved(m, local))
    np.testing.assert_allclose(h["p"], moved(m, local), atol=atol)
    np.testing.assert_allclose(h["uv"], uv, atol=2e-5)
    dpdu = phi_max * np.column_stack([-local[:, 1], local[:, 0], np.zeros(len(local))]) @ m[:3, :3].T
    np.testing.assert_allclose(h["dpdu"], dpdu, atol=dpdu_atol)
    return h


def pbrt_emitter(folder, capfd, lines):
    """The one analytic shape of a pbrt-v4 file whose `lines` place it under an area light of
    `power` 10, read without a warning, and its emitted radiance (rgb)."""
    path = folder / "s.pbrt"
    path.write_text(PBRT_EMITTER.format(lines=lines))
    scene = load_scene(str(path))
    assert "warning" not in capfd.readouterr().err
    (shape,) = scene.shapes
    assert not scene.meshes
    return shape, scene.materials.rows["emission"][shape.material][:3]
