"""What bidirectional path tracing (kernels/bdpt.cl) takes of a scene and its settings: the
depth its program is built for, the light sampler it needs, and the one line that says what it
cannot render yet."""

from pathtrace.cameras.registry import supports_importance
from pathtrace.errors import UserError, warn

MAX_DEPTH = 10
"""The longest path BDPT draws, in the path tracer's depth (vertices after the camera): its
subpaths' vertices live in each work-item's private arrays, sized at compile time. pbrt-v4's
BDPT defaults to 5 bounces (depth 6)."""

_warned = set()


def depth(max_depth: int, integrator: str = "bdpt") -> int:
    """The depth a BDPT program (bdpt's, or ptracer's) is built for: max_depth, or MAX_DEPTH where
    that asks for more (0: no limit), said once per value and integrator. BDPT has no Russian
    roulette (pbrt-v4's has none): paths end at this depth."""
    if 1 <= max_depth <= MAX_DEPTH:
        return max_depth
    if (max_depth, integrator) not in _warned:
        _warned.add((max_depth, integrator))
        asked = "no limit" if max_depth == 0 else f"max_depth {max_depth}"
        warn(f"{integrator}: paths end at depth {MAX_DEPTH} (the render's settings ask for {asked})")
    return MAX_DEPTH


def check(name: str, features, integrator: str, lights):
    """Raises a UserError, one line, for what `integrator` (bdpt or ptracer) cannot render yet
    in a scene (its file, or its name) whose program needs `features` (app/device/features.py) and whose light table
    is `lights`: a camera without importance (app/cameras/: Camera.importance); for light tracing
    alone, light from the environment, which the camera sees directly where nothing is in the
    way, and light tracing cannot join to the lens (its light subpaths leave a disk across the
    scene, kernels/lights.cl: leave_world_disk)."""
    if not supports_importance(features.camera):
        raise UserError(f"{name}: integrator {integrator}: the {features.camera} camera has no importance to join "
                        "light subpaths to yet (the path tracer renders it)")
    if integrator == "ptracer" and lights.env_pick > 0:
        raise UserError(f"{name}: integrator ptracer: the environment, seen directly, is not reached by light "
                        "tracing (BDPT and the path tracer render it)")
