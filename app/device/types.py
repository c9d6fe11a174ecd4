"""NumPy mirrors of the structs in kernels/types.h, field for field (tests/test_types.py checks
them against the device's own sizeof and offsetof)."""

import numpy as np

TRIANGLE = np.dtype([
    ("v0", np.float32, 4),          # w: first shading normal's index (int bits), or -1
    ("v1", np.float32, 4),          # w: first texture coordinate's index (int bits), or -1
    ("v2", np.float32, 4),
])

MATERIAL = np.dtype([
    ("p0", np.float32, 4),          # the BSDF's parameters, in the slots its type declares
    ("p1", np.float32, 4),
    ("p2", np.float32, 4),
    ("emission", np.float32, 4),    # Le rgb
    ("type", np.int32),             # BSDF tag (app/materials/registry.py)
    ("flags", np.int32),            # MATERIAL_* bits
    ("continuation", np.float32),   # the report's Russian roulette: probability of going on
    ("textures", np.int32),         # first row of its TEXTURE_BINDINGs, or -1
    ("table", np.float32, 16),      # more of the BSDF's slots (a tabulated function among them)
])

TEXTURE_BINDING = np.dtype([
    ("texture", np.int32),          # row of the texture table
    ("slot", np.int32),             # the first of the material's floats it gives (p0.x: 0)
    ("width", np.int32),            # 3: a colour; 1: a number
    ("last", np.int32),             # 1 on a material's last binding
])

TEXTURE = np.dtype([
    ("to_u", np.float32, 4),        # the uv transform's rows
    ("to_v", np.float32, 4),
    ("value", np.float32, (3, 4)),  # constant inputs
    ("input", np.int32, 3),         # a texture input: its row, -2 - r: register r, -1: value[k]
    ("type", np.int32),             # TEXTURE_* tag (app/textures/registry.py)
    ("width", np.int32),
    ("height", np.int32),
    ("texels", np.uint32),          # first texel, in 4-byte words of the texel buffer
    ("format", np.int32),
    ("channels", np.int32),
    ("wrap", np.int32),
    ("filter", np.int32),
    ("program", np.int32),          # a combining texture's first step (kernels/texture.cl), or -1
])

BVH_NODE = np.dtype([(name, np.float32, 4) for name in ("lo_x", "lo_y", "lo_z", "hi_x", "hi_y", "hi_z")]
                    + [("index", np.int32, 4), ("count", np.int32, 4)])   # count > 0: spheres; < 0: triangles; 0: inner or unused

INSTANCE = np.dtype([
    ("to_world", np.float32, (3, 4)),   # rows of the 3x4 world-from-object transform
    ("to_object", np.float32, (3, 4)),  # and of its inverse
    ("root", np.int32),                 # the object's BVH root node
    ("pad", np.int32, 3),
])

RENDER_PARAMS = np.dtype([
    ("eye", np.float32, 4),
    ("forward", np.float32, 4),
    ("right", np.float32, 4),
    ("up", np.float32, 4),
    ("env_scale", np.float32, 4),
    ("lens", np.float32, 4),        # what else the camera type reads (app/cameras/: Camera.lens)
    ("filter", np.float32, 4),      # the pixel filter's parameters (kernels/filters/)
    ("world", np.float32, 4),       # the scene's bounding sphere: centre, radius (CompiledScene)
    ("env_frame", np.float32, (3, 4)),  # rows of the map-from-world rotation (Environment.map_from_world)
    ("width", np.int32),
    ("height", np.int32),
    ("sample_start", np.uint32),
    ("sample_count", np.uint32),
    ("seed", np.uint32),
    ("max_depth", np.int32),
    ("env_width", np.int32),
    ("env_height", np.int32),
    ("env_row_scale", np.float32),  # the map's row at v = acos(y) / pi: v * scale + offset (Environment.rows)
    ("env_row_offset", np.float32),
    ("num_lights", np.int32),
    ("env_pick", np.float32),
    ("num_spheres", np.int32),
    ("rr_depth", np.int32),
    ("row_start", np.int32),        # rows [row_start, row_end) of the image
    ("row_end", np.int32),
    ("camera_medium", np.int32),    # the camera's medium (a row of the media table), or -1
    ("camera_type", np.int32),      # a GENERIC program's run-time choices (kernels/types.h)
    ("filter_type", np.int32),
    ("rr_rule", np.int32),
    ("layout", np.int32),           # the compiled scene's LAYOUT_* bits (kernels/scene.cl)
    ("pad", np.int32, 3),           # to the float4s' alignment, as the device pads the struct
])

LIGHT = np.dtype([
    ("keep", np.uint32),            # the keep probability times 2^32 (lights.keep_threshold)
    ("alias", np.int32),
    ("pick", np.float32),
    ("type", np.int32),             # LIGHT_* tag (app/lights/registry.py)
    ("prim", np.int32),             # an area light's primitive, else -1
    ("pad", np.int32, 3),
    ("p0", np.float32, 4),          # the type's values, in the slots it declares (app/lights/)
    ("p1", np.float32, 4),
    ("p2", np.float32, 4),
])

LIGHT_NODE = np.dtype([
    ("lo", np.float32, 4),          # box low corner; w: total power
    ("hi", np.float32, 4),          # box high corner; w: cos(theta_o)
    ("axis", np.float32, 4),        # normals' cone axis; w: cos(theta_e)
    ("child", np.int32),            # first child, or -1: a leaf
    ("parent", np.int32),           # -1: the root
    ("light", np.int32),            # a leaf's light table entry
    ("pad", np.int32),
])

MEDIUM = np.dtype([
    ("sigma_s", np.float32, 4),     # scattering coefficient rgb; w: the phase function's g
    ("sigma_t", np.float32, 4),     # extinction coefficient rgb
])

PATH_RECORD = np.dtype([(name, np.float32, 4) for name in
                        ("o", "d", "throughput", "radiance", "prev_x", "prev_n", "ratios")]
                       + [("rng", np.uint32, 4)])   # kernels/types.h PathRecord: the continuation
                                                    # queue's entries

PHOTON = np.dtype([(name, np.float32, 4) for name in ("p", "beta", "wo", "n")])   # kernels/types.h Photon:
                                                    # a caustic photon (kernels/photons.cl)
PHOTON_MAP = np.dtype([("radius", np.float32), ("paths", np.int32), ("mask", np.uint32), ("pad", np.int32)])
