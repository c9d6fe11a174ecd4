"""The scenes `pathtrace bench` times where --scenes names none: the report's table (report.py)
and the first image's (first_image.py); and the scenes it writes on demand (scenes.py). Here, in a module that imports nothing, because the
command's help lists them: building the command line's parser loads no PyOpenCL (issue #60)."""

TARGET_SCENES = ("simple", "spheres8k", "spheres64k",
                 "simple-diffuse", "spheres8k-diffuse", "spheres64k-diffuse", "teapot-sky",
                 "teapot-textured")
FIRST_IMAGE_SCENES = ("simple", "cornell-box", "teapot-sky", "meshes850", "meshes850-obj")
GENERATED_FILES = ("tori400-textured", "tori400-materials", "meshes850-obj")      # pathtrace.bench.scenes
