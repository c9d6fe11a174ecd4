"""The viewer's screenshots: the image as shown, tonemapped (PNG) and as radiance (EXR), written
in a thread of their own. A part of the Viewer (app/viewer/window.py), which is one."""

import datetime
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError


class Screenshots:
    """The Viewer's screenshots (its writer thread is made in Viewer.__init__)."""

    def screenshot(self, scripted: bool = False):
        """Writes the image as shown: tonemapped (PNG) and as radiance (EXR); where it is the
        denoised one, the EXR keeps the noisy one as its layer "noisy". The pass under way is
        finished first, so that every pixel holds the same samples. The image is read now; it is
        denoised and written in a thread of its own, so that the window stays live (Esc closes
        it at once) while a large image is denoised. Returns the future of the two paths (None
        where writing failed, which the panel's message line then says). `scripted`: a script's
        `--screenshot`, whose failure the future raises, and which waits for the kernels of an
        integrator asked for that are still building, so that it shows that one. It is always of the
        scene's size: where the image shown is a preview's (a move's, a scene's first) or a
        draft's, or no pass has ended yet, a pass at the scene's size is rendered first (a
        script's `view --frames N --screenshot` writes the scene's size whatever N)."""
        if scripted and self.requested_integrator is not None:    # (set_settings waits for its kernels)
            self.renderer.set_settings(integrator=self.requested_integrator)
            self.requested_integrator = None
        self.progressive.finish_pass()
        r = self.renderer
        if self.scale != 1 or r.samples == 0:
            self.scale, self.draft = 1, False
            r.resize(*self.size)
            r.add_samples(1)
            r.finish()
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S-%f")[:-3]
        base = self.screenshot_dir / f"pathtrace-{r.scene.name}-{stamp}"
        noisy = r.mean()
        denoised = self.denoised_at is not None and self.denoised_at[0] == r.resets and self.denoise and self.resting
        aovs = r.read_aovs() if denoised else None
        look = (self.exposure, self.tonemap)
        self.set_message(f"saving {base.name} ({r.samples} spp{', denoised' if denoised else ''})")
        return self._writer.submit(self._save_screenshot, base, noisy, aovs, look, r.samples, scripted)

    def _save_screenshot(self, base: Path, noisy: np.ndarray, aovs, look: tuple, samples: int, scripted=False):
        """In the screenshot thread: denoised where `aovs` are given, then both files written."""
        from pathtrace.io.images import Output, write_images
        shown, layers = noisy, {}
        try:
            if aovs is not None:
                shown, layers = self._denoise(noisy, aovs["albedo"], aovs["normal"]), {"noisy": noisy}
            outputs = [Output(base.with_suffix(".png"), shown), Output(base.with_suffix(".exr"), shown, layers)]
            base.parent.mkdir(parents=True, exist_ok=True)
            write_images(outputs, *look, what="screenshot")
        except (UserError, OSError) as e:
            if scripted:
                raise UserError(f"screenshot: {e}") from None
            self.set_message(f"screenshot failed: {e}", error=True)
            return None
        finally:
            self.redraw_soon()
        paths = [out.path for out in outputs]
        self.set_message(f"saved {paths[0]} and .exr ({samples} spp{', denoised' if layers else ''})")
        return paths
