"""pbrt-v4's scene-wide options as pathtrace's render settings and camera: Camera (its type by
the camera types' pbrt-v4 names, app/cameras/, read once the film's size is known), Film,
Sampler, Integrator and PixelFilter, with pbrt-v4's defaults. The camera's CTM is
camera-from-world; camera space looks down +z with +y up and +x to the image's right, so that
a plain `LookAt` gives the mirror image of a right-handed camera (Camera.mirrored); `fov` spans
the shorter image axis; `maxdepth` counts bounces: pbrt's N is pathtrace's (Mitsuba's) N + 1
vertices. The pbrt reader (reader.py) is an OptionDirectives."""

import numpy as np

from pathtrace import cameras
from pathtrace.cameras import Camera
from pathtrace.cameras.camera import FILM, TO_WORLD, frame_of
from pathtrace.errors import warn
from pathtrace import filters
from pathtrace.scene.pbrt.tokens import ParamList, parameters, string
from pathtrace.scene.meshes import MAX_COORDINATE
from pathtrace.scene import settings
from pathtrace.scene.known_names import known, refuse_unknown_type


class OptionDirectives:
    """The directives of the scene-wide options, on the pbrt reader's settings, filter and
    camera_params."""

    def _camera(self, tokens, offset):
        kind = string(tokens, "Camera")
        params = parameters(tokens)
        # pbrt-v4: the camera is in the current outside medium
        self.camera_params = (kind, params, tokens.where(offset), self.state.ctm.copy(),
                              self.medium_row(self.state.media[1], tokens.where(offset)))
        self.named_systems["camera"] = self.inverse(tokens.where(offset), "the camera")

    def make_camera(self) -> Camera:
        """pathtrace's camera for pbrt's, once the film's size is known, by the camera types'
        declared pbrt-v4 names (pbrt-v4's defaults where there is no Camera directive)."""
        kind, params, where, ctm, _ = self.camera_params or ("perspective", ParamList(None), str(self.path),
                                                             np.eye(4), -1)
        cls = cameras.registry.format_class("pbrt", kind)
        if cls is None:
            refuse_unknown_type("pbrt", "camera", kind, where)
            warn(f"{where}: pathtrace has no {kind} camera; it uses a perspective one of pbrt-v4's defaults")
            kind, params, cls = "perspective", ParamList(None), cameras.registry.format_class("pbrt", "perspective")
        world_from_camera = np.linalg.inv(ctm)
        given = {FILM: (self.settings.width, self.settings.height), TO_WORLD: world_from_camera}
        values = self.read_declared(cls.parameters + cls.format_only, params, where, given)
        try:
            camera = cls.from_file("pbrt", values, given, frame_of(world_from_camera, x_right=True),
                                   lambda text, name=None: warn(f"{params.where(name) if name else where}: {text}"))
        except ValueError as e:
            self.mapper.fail(params, where, e, cameras.registry.FIELDS)
        self.unused(params, "camera", kind)
        return camera

    def _film(self, tokens, offset):
        kind = string(tokens, "Film")
        params = parameters(tokens)
        refuse_unknown_type("pbrt", "film", kind, tokens.where(offset))     # pbrt-v4's rgb, gbuffer and spectral
        values = self.read_declared(settings.Film, params, tokens.where(offset))
        self.settings.width, self.settings.height = values["width"], values["height"]
        for name in ("cropwindow", "pixelbounds"):
            if params.type_of(name):
                params.floats(name, ("float",) if name == "cropwindow" else ("integer",))
                warn(f"{params.where(name)}: pathtrace renders the whole film; ignored")
        self.unused(params, "film", kind)

    def _sampler(self, tokens, offset):
        """The samples per pixel, as pbrt-v4's samplers take them (settings.Sampler: `pixelsamples`,
        16; a stratified one's xsamples times ysamples). Their seeds, jitter and randomization are
        their own: warned of, as any name not read."""
        kind = string(tokens, "Sampler")
        params = parameters(tokens)
        sampler = settings.SAMPLERS["pbrt"].get(kind, settings.Sampler)
        self.settings.spp = self.read_declared(sampler, params, tokens.where(offset))["spp"]
        self.unused(params, "sampler", kind)

    def _integrator(self, tokens, offset):
        kind = string(tokens, "Integrator")
        params = parameters(tokens)
        refuse_unknown_type("pbrt", "integrator", kind, tokens.where(offset))
        self.settings.integrator, note = settings.Integrator.types["pbrt"].get(
            kind, ("path", f"pathtrace renders with its path tracer instead of {kind}"))
        if kind == "sppm":
            # the paths photon mapping finds and BDPT does not, photons estimate
            # (kernels/photons.cl), from pbrt-v4's initial search radius (SPPMIntegrator::Create)
            radius = params.float("radius", 1.0)
            if not 0 < radius <= MAX_COORDINATE:
                params.fail("radius", f"must be in (0, {MAX_COORDINATE:g}], got {radius}")
            self.settings.photon_radius = radius
            note = f"pathtrace renders sppm with bdpt and caustic photons of radius {radius:g}"
        if note:
            warn(f"{tokens.where(offset)}: {note}")
        # what that integrator reads of pathtrace's settings (bdpt, mlt and sppm no light sampler)
        names = known("pbrt", f"integrator {kind}")
        taken = tuple(p for p in settings.Integrator.parameters if names is None or p.pbrt in names)
        values = self.read_declared(taken, params, tokens.where(offset))
        self.settings.max_depth = values["max_depth"]
        self.settings.light_sampler = values.get("light_sampler", self.settings.light_sampler)
        if names is not None and "regularize" in names and params.bool("regularize", False):
            warn(f"{params.where('regularize')}: pathtrace does not regularize; ignored")
        if names is not None:
            self.unused(params, "integrator", kind)
        params.ignore()            # another integrator's settings: it is replaced whole, with its warning

    def _pixel_filter(self, tokens, offset):
        """A filter by its type's declared pbrt-v4 names (app/filters.py); pbrt-v4's default for
        one of negative lobes."""
        kind = string(tokens, "PixelFilter")
        params, where, given = parameters(tokens), tokens.where(offset), {}
        try:
            found = filters.format_type("pbrt", kind, lambda text: warn(f"{where}: {text}"))
        except ValueError as e:
            tokens.fail(offset, str(e))
        if found is None:
            params.ignore()
            self.filter = filters.format_default("pbrt")
            return
        values = self.read_declared(found, params, where, given)
        try:
            self.filter = found.make(values, given, lambda text: warn(f"{where}: {text}"))
        except ValueError as e:
            self.mapper.fail(params, where, e, found.parameters)
        self.unused(params, "filter", kind)


OPTION_DIRECTIVES = {
    "Camera": OptionDirectives._camera,
    "Film": OptionDirectives._film,
    "Sampler": OptionDirectives._sampler,
    "Integrator": OptionDirectives._integrator,
    "PixelFilter": OptionDirectives._pixel_filter,
}
