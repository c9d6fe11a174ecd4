"""Fly-through camera controls: W/A/S/D move, Q/E (or Ctrl/Space) go down and up, the mouse looks
around, the wheel changes speed, Shift is faster. Movement is per second of frame time, so it
does not depend on the frame rate."""

from dataclasses import dataclass, field

import numpy as np

from pathtrace.cameras import Camera

# key names, mapped to GLFW's codes by the window
MOVES = {
    "W": (0, 0, 1), "S": (0, 0, -1), "D": (1, 0, 0), "A": (-1, 0, 0),
    "E": (0, 1, 0), "SPACE": (0, 1, 0), "Q": (0, -1, 0), "LEFT_CONTROL": (0, -1, 0),
}
MOUSE_DEGREES_PER_PIXEL = 0.15


@dataclass
class FlyControls:
    speed: float = 2.0                  # units per second
    fast_factor: float = 4.0
    held: set = field(default_factory=set)

    def update(self, camera: Camera, dt: float, look_dx: float = 0.0, look_dy: float = 0.0,
               fast: bool = False) -> bool:
        """Moves and turns `camera` in place for a frame of `dt` seconds with the keys in
        self.held and a mouse move of (look_dx, look_dy) pixels. Returns whether it moved."""
        moved = False
        forward = camera.look_at - camera.eye
        distance = np.linalg.norm(forward)
        forward /= distance
        up = camera.up / np.linalg.norm(camera.up)
        # the image's right: forward x up, or its opposite for a mirrored camera (a pbrt LookAt)
        side = -1.0 if camera.mirrored else 1.0
        if look_dx or look_dy:
            yaw = -side * np.radians(look_dx * MOUSE_DEGREES_PER_PIXEL)
            pitch = -side * np.radians(look_dy * MOUSE_DEGREES_PER_PIXEL)
            forward = _rotate(forward, up, yaw)
            right = side * np.cross(forward, up)
            right /= np.linalg.norm(right)
            turned = _rotate(forward, right, pitch)
            if abs(np.dot(turned, up)) < 0.995:     # never look straight up or down
                forward = turned
            moved = True
        right = side * np.cross(forward, up)
        right /= np.linalg.norm(right)
        step = np.zeros(3)
        for key in self.held:
            if key in MOVES:
                x, y, z = MOVES[key]
                step += x * right + y * up + z * forward
        if np.any(step):
            camera.eye = camera.eye + step / np.linalg.norm(step) * self.speed * \
                (self.fast_factor if fast else 1.0) * dt
            moved = True
        camera.look_at = camera.eye + forward * distance
        return moved

    def scroll(self, amount: float):
        """The wheel scales the speed by 1.25 per notch."""
        self.speed = float(np.clip(self.speed * 1.25 ** amount, 0.01, 1000.0))


def speed_for(camera, radius: float) -> float:
    """A speed (units per second) at the scene's scale: a quarter of the distance from `camera`'s
    eye to the point it looks at, at most a fifth of `radius`, the compiled scene's bounding
    sphere's (CompiledScene.radius: a tenth of its box's diagonal, instances included; a camera
    whose look-at point is far off, as a pbrt LookAt may give, would carry out of a small scene
    in a second), and the default where neither says anything. The wheel changes it from there."""
    distance = float(np.linalg.norm(camera.look_at - camera.eye))
    candidates = [v for v in (0.25 * distance, 0.2 * radius) if v > 0 and np.isfinite(v)]
    return float(np.clip(min(candidates), 0.01, 1000.0)) if candidates else FlyControls.speed


def _rotate(v, axis, angle):
    """Rodrigues' rotation of v about a unit axis."""
    return v * np.cos(angle) + np.cross(axis, v) * np.sin(angle) + axis * np.dot(axis, v) * (1 - np.cos(angle))


def pick_ray(camera: Camera, width: int, height: int, x: float, y: float):
    """The camera ray through image point (x, y), pixels from the top-left corner, from the
    lens's centre."""
    return camera.ray(width / height, 2 * x / width - 1, 1 - 2 * y / height)
