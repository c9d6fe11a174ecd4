"""The progressive renderer: device buffers for a scene and an accumulation buffer, to which
each add_samples() call adds samples per pixel. The command line, the benchmarks and the viewer
all drive this API; it imports nothing from the window or the GUI."""

import time
from dataclasses import replace

import numpy as np
import pyopencl as cl

from app.bvh import build_bvh
from app.camera import Camera
from app.device import Backend
from app.environment import Environment
from app.lights import build_light_table
from app.scene import Scene
from app.types import RENDER_PARAMS, pack_materials


class Renderer:
    def __init__(self, backend: Backend, scene: Scene, width: int = None, height: int = None):
        self.backend = backend
        self.kernels = {False: cl.Kernel(backend.program, "render"),
                        True: cl.Kernel(backend.program, "render_nee")}
        self._buffers = {}
        self.width = self.height = 0
        self.samples = 0          # samples per pixel accumulated so far
        self.settings = scene.settings
        self.set_scene(scene)
        self.resize(width or scene.settings.width, height or scene.settings.height)

    # --- what is rendered ------------------------------------------------------------------
    def set_scene(self, scene: Scene):
        """Builds the BVH and uploads spheres, materials and environment; resets."""
        self.scene = scene
        self.camera = scene.camera.copy()
        start = time.perf_counter()
        self.bvh = build_bvh(scene.spheres)
        self.bvh_seconds = time.perf_counter() - start
        self._upload("nodes", self.bvh.nodes)
        self._upload("spheres", scene.spheres[self.bvh.order])
        self.environment = scene.environment
        self._upload_environment()
        self.upload_materials()

    def upload_materials(self):
        """Uploads the scene's materials and light table (after an edit of scene.rho_d etc.);
        resets."""
        s, o = self.scene, self.bvh.order
        self._upload("materials", pack_materials(s.rho_d[o], s.rho_s[o], s.exponent[o], s.emission[o]))
        self._upload_lights()
        self.reset()

    def set_environment(self, environment: Environment):
        self.environment = environment
        self._upload_environment()
        self._upload_lights()
        self.reset()

    def _upload_environment(self):
        self._upload("env", self.environment.rgba())
        marginal, conditional = self.environment.sampling_cdfs()
        self._upload("env_marginal", marginal)
        self._upload("env_conditional", conditional)

    def _upload_lights(self):
        o = self.bvh.order
        self.lights = build_light_table(self.scene.spheres[o], self.scene.emission[o], self.environment)
        self._upload("lights", self.lights.lights)
        self._upload("light_pick", self.lights.pick)

    def set_camera(self, camera: Camera):
        self.camera = camera.copy()
        self.reset()

    def set_settings(self, **changes):
        self.settings = replace(self.settings, **changes)
        self.reset()

    def resize(self, width: int, height: int):
        if (width, height) == (self.width, self.height):
            return
        self.width, self.height = width, height
        nbytes = width * height * 16
        for name in ("sum", "sum_sq"):
            self._buffers[name] = cl.Buffer(self.backend.context, cl.mem_flags.READ_WRITE, nbytes)
        self.reset()

    def reset(self):
        """Restarts the progressive average."""
        if "sum" in self._buffers:
            for name in ("sum", "sum_sq"):
                cl.enqueue_fill_buffer(self.backend.queue, self._buffers[name], np.float32(0), 0,
                                       self.width * self.height * 16)
        self.samples = 0

    # --- rendering -------------------------------------------------------------------------
    def params(self, sample_count: int) -> np.ndarray:
        p = np.zeros((), RENDER_PARAMS)
        forward, right, up = self.camera.basis(self.width / self.height)
        p["eye"][:3] = self.camera.eye
        p["forward"][:3], p["right"][:3], p["up"][:3] = forward, right, up
        p["env_scale"][:3] = self.environment.intensity
        p["width"], p["height"] = self.width, self.height
        p["sample_start"], p["sample_count"] = self.samples, sample_count
        p["seed"] = self.settings.seed
        p["max_depth"] = self.settings.max_depth
        p["russian_roulette"] = int(self.settings.russian_roulette)
        h, w, _ = self.environment.image.shape
        p["env_width"], p["env_height"] = w, h
        p["env_rotation"] = self.environment.rotation / 360.0
        p["num_lights"] = self.lights.count
        p["env_pick"] = self.lights.env_pick
        return p

    def add_samples(self, count: int = 1) -> cl.Event:
        """Queues one launch that adds `count` samples to every pixel; returns its event."""
        b = self._buffers
        kernel = self.kernels[self.settings.nee]
        kernel.set_args(b["nodes"], b["spheres"], b["materials"], b["env"], b["lights"],
                             b["light_pick"], b["env_marginal"], b["env_conditional"],
                             self.params(count), b["sum"], b["sum_sq"])
        local = (8, 8)
        global_size = tuple(-(-n // l) * l for n, l in zip((self.width, self.height), local))
        event = cl.enqueue_nd_range_kernel(self.backend.queue, kernel, global_size, local)
        self.samples += count
        return event

    def finish(self):
        self.backend.queue.finish()

    def _read(self, name, out=None) -> np.ndarray:
        if out is None:
            out = np.empty((self.height, self.width, 4), np.float32)
        cl.enqueue_copy(self.backend.queue, out, self._buffers[name])
        return out

    def read_sum(self, out=None) -> np.ndarray:
        """The raw accumulation buffer, (H, W, 4) float32: radiance sums in rgb, sample count
        in a; into `out` if given (the viewer reuses one array for every upload)."""
        return self._read("sum", out)

    def mean(self) -> np.ndarray:
        """The image so far: mean radiance per pixel, (H, W, 3) float32."""
        return self._read("sum")[..., :3] / max(self.samples, 1)

    def rays_traced(self) -> int:
        """Rays traced since the last reset (camera rays and bounces), all pixels together."""
        return int(self._read("sum_sq")[..., 3].sum(dtype=np.float64))

    def variance(self) -> np.ndarray:
        """The per-sample variance of each pixel and channel (of one sample, not of the mean)."""
        n = max(self.samples, 1)
        m = self._read("sum")[..., :3].astype(np.float64) / n
        return np.maximum(self._read("sum_sq")[..., :3] / n - m * m, 0.0).astype(np.float32)

    def _upload(self, name, array):
        array = np.ascontiguousarray(array)
        self._buffers[name] = cl.Buffer(self.backend.context,
                                        cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                                        hostbuf=array)
