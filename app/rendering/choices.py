"""The names a render's enumerated settings (RenderSettings) take, the path queue's bounds, and
the tone curves its image is shown and written with: here, in a module that imports nothing, so
that the command line builds its parser and refuses a bad option without loading NumPy, PyOpenCL
or the scene modules (issue #60)."""

# How paths end (kernels/integrator.cl, RR_*): "throughput", Russian roulette on the path's
# throughput from depth 5 on (Mitsuba 3's and pbrt-v4's); "albedo", the report's, at every
# vertex with the material's albedo; "off", at max_depth only.
RUSSIAN_ROULETTE = ("off", "albedo", "throughput")
MAX_PATH_QUEUE = 64     # RenderSettings.path_queue's largest value (no path that long is short)
PATH_QUEUE_AUTO = -1    # RenderSettings.path_queue "auto": chosen by trial renders (pathtrace.rendering.renderer)
# The estimators a render can use: "path", the path tracer (kernels/integrator.cl); "bdpt",
# bidirectional path tracing (kernels/bdpt.cl, app/rendering/bdpt.py); "ptracer", its light tracing alone
# (Mitsuba 3's particle tracer).
INTEGRATORS = ("path", "bdpt", "ptracer")
LIGHT_SAMPLERS = ("auto", "power", "tree")   # how next-event estimation chooses a light (pathtrace.lights.table)
FILTERS = ("box", "tent", "gaussian")    # the pixel filters, in RenderParams.filter_type's order (pathtrace.filters)
TONEMAPS = ("standard", "aces")             # the tone curves of pathtrace.io.tonecurve
