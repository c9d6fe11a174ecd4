"""pathtrace.scene.mitsuba_writer: the Mitsuba 3 twin of a benchmark scene says what the scene
says. Read back by pathtrace's own Mitsuba reader (a reader tested against Mitsuba's renders in
test_reference.py), it has the same shapes, materials, camera and sky, and renders the same image
to within noise; what it cannot say is refused in one line."""

from dataclasses import replace

import numpy as np
import pytest

from pathtrace import api
from pathtrace.cameras import ThinLensCamera
from pathtrace.errors import UserError
from pathtrace.scene import load_scene
from pathtrace.scene.mitsuba_writer import write_mitsuba


@pytest.mark.parametrize("name", ["simple-diffuse", "teapot-sky"])
def test_twin_reads_back_as_the_scene(tmp_path, name):
    scene = load_scene(name).with_settings(width=48, height=27, spp=64, max_depth=8)
    twin = load_scene(str(write_mitsuba(scene, tmp_path / f"{name}.xml")))
    assert np.allclose(twin.spheres, scene.spheres, atol=1e-6)
    assert [len(m.faces) for m in twin.meshes] == [len(m.faces) for m in scene.meshes]
    for a, b in zip(twin.meshes, scene.meshes):
        assert np.allclose(a.vertices, b.vertices, atol=1e-5) and (a.normals is None) == (b.normals is None)
    assert np.allclose(twin.camera.eye, scene.camera.eye) and abs(twin.camera.vfov - scene.camera.vfov) < 1e-6
    assert (twin.settings.width, twin.settings.height, twin.settings.spp, twin.settings.max_depth) == (48, 27, 64, 8)
    assert np.allclose(twin.environment.image[0, 0, :3] * twin.environment.intensity,
                       scene.environment.image[0, 0, :3] * scene.environment.intensity)
    ours, theirs = (api.render(s, device="cpu", seed=k) for k, s in enumerate((scene, twin)))
    assert abs(ours.mean() - theirs.mean()) < 0.02 * ours.mean(), (ours.mean(), theirs.mean())


def test_what_a_twin_cannot_say_is_refused(tmp_path):
    with pytest.raises(UserError, match="material .*only diffuse and black materials"):
        write_mitsuba(load_scene("simple"), tmp_path / "s.xml")          # its Phong spheres
    scene = load_scene("simple-diffuse")
    with pytest.raises(UserError, match="only pinhole perspective cameras"):
        write_mitsuba(replace(scene, camera=ThinLensCamera([0, 2, 9], [0, 1, 0], [0, 1, 0], 40.0, aperture_radius=0.1)),
                      tmp_path / "s.xml")
    with pytest.raises(UserError, match="only diffuse and black materials without textures"):
        write_mitsuba(load_scene("teapot-textured"), tmp_path / "t.xml")
