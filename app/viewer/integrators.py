"""The viewer's choice of integrator (the panel's "integrator": the path tracer, BDPT or light
tracing): the kernels of the one asked for built in the background while the image goes on, then
switched to. A part of the Viewer (app/viewer/window.py), which is one."""

from pathtrace.errors import UserError


class IntegratorSwitch:
    """The Viewer's switch of integrator, asked for by the panel and made between turns."""

    requested_integrator = None   # the integrator the panel asked for, until its kernels are built

    def request_integrator(self, name: str):
        self.clear_error("integrator")
        self.requested_integrator = None if name == self.renderer.settings.integrator else name
        self.redraw_soon()

    def switch_integrator(self):
        """Called each turn: switches to the requested integrator once its kernels are built, their
        build going on in the background meanwhile (the accumulation restarts: the estimators differ);
        one that cannot render the scene, or whose kernels did not build, is the panel's error line."""
        name = self.requested_integrator
        if name is None:
            return
        try:
            ready = self.renderer.integrator_ready(name)
        except UserError as e:
            self.requested_integrator = None
            self.set_message(str(e), error=True, about="integrator")
            return
        if ready:
            self.requested_integrator = None
            self.renderer.set_settings(integrator=name)
            self.set_message(f"rendering with {name}")
            self.redraw_soon()
