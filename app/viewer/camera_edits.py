"""The viewer's changes of the camera besides flying it (app/viewer/controls.py): back to the
scene's camera (R), another camera type (the panel's), the lens focused on the surface under the
cursor (Ctrl + click). A part of the Viewer (app/viewer/window.py), which is one."""

import time

import numpy as np

from pathtrace.cameras import CAMERAS


class CameraEdits:
    """The Viewer's camera edits; `camera_fields` (the Viewer's) holds the sliders' last values."""

    def reset_camera(self):
        """R: back to the scene's own camera."""
        self.renderer.set_camera(self.renderer.scene.camera)
        self.last_move = time.perf_counter()

    def switch_camera_type(self, kind: str):
        """The panel's camera type: a camera of type `kind` with this one's frame, its sliders'
        fields as the cameras had them before (perspective's vfov through the spherical camera,
        which has none); it returns it."""
        camera = self.renderer.camera
        self.camera_fields.update({name: getattr(camera, name) for name in camera.sliders})
        camera = camera.as_type(kind, **{name: self.camera_fields[name] for name in CAMERAS[kind].sliders
                                         if name in self.camera_fields})
        self.renderer.set_camera(camera)
        self.clear_error("integrator")
        return self.renderer.camera

    def focus_at(self, origin, direction):
        """Puts the plane in focus through the surface seen along a ray (a camera with a
        focus_distance; the aperture stays as it is). Returns whether a surface was there."""
        camera = self.renderer.camera
        t = self.renderer.hit_distance(origin, direction)
        if not hasattr(camera, "focus_distance") or t is None:
            return False
        forward = camera.frame()[0]
        camera.focus_distance = float(t * np.dot(direction, forward))
        self.renderer.set_camera(camera)
        return True
