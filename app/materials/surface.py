"""What any material carries besides its BSDF's parameters: emission, two sides, an alpha mask
and a normal or bump map (Material's own fields), declared once (app/parameters.py) as a TOML
material table's keys and Mitsuba 3's wrapper plugins, and set on a Material, checked together,
by `dressed`. pbrt-v4 gives them to the shape, its area light and its material: its reader sets
them one at a time."""

from dataclasses import replace

from pathtrace.materials.table import PERTURBATIONS, Material, check_bump_map, scaled_bump_map, surface_problem
from pathtrace.lights.light import MAX_RADIANCE
from pathtrace.parameters import Parameter, out_of_range
from pathtrace.textures import TEXTURES, Texture

# Mitsuba 3 gives a field by a plugin wrapped round a nested BSDF: its Mitsuba name is the
# plugin's, "plugin.property" for a property of it, the plugin alone for the plugin's presence (a
# bool) or its one texture, whatever that texture's name (a bumpmap's)
# pbrt-v4 takes any alpha number: its stochastic alpha test (GeometricPrimitive::Intersect) keeps
# every hit at 1 or more and none at 0 or less, as an opacity clamped to [0, 1] does; an alpha
# texture beyond [0, 1] is refused, as the opacity's range refuses one in every format
SURFACE = (
    Parameter("Le", "color", 0.0, low=0.0, high=MAX_RADIANCE, texture=True,
              doc="emitted radiance (beyond 1e20 the sums of samples overflow)"),
    Parameter("emits_back", "bool", False, doc="its emission leaves its back too (pbrt-v4's two-sided area lights)"),
    Parameter("twosided", "bool", False, doc="the BSDF on both sides (not for one that transmits)", mitsuba="twosided"),
    Parameter("opacity", "number", 1.0, low=0.0, high=1.0, texture=True, mitsuba="mask.opacity", mitsuba_default=0.5,
              pbrt="alpha", from_pbrt=lambda alpha, given: alpha if isinstance(alpha, Texture) else min(max(alpha, 0.0), 1.0),
              doc="an alpha mask: the probability that a ray meets the surface (a texture's luminance)"),
    Parameter("normal_map", "texture", optional=True, doc="tangent-space normals, 2 rgb - 1 (a bitmap, raw)",
              mitsuba="normalmap.normalmap"),
    Parameter("bump_map", "texture", optional=True, doc="heights: a bitmap, or a scale of one by a number",
              mitsuba="bumpmap"),
    Parameter("bump_scale", "number", 1.0, doc="a factor on the bump map's heights", mitsuba="bumpmap.scale"),
    Parameter("perturbation", "name", "mitsuba", choices=PERTURBATIONS,
              doc="how a normal or bump map perturbs: as Mitsuba 3's or as pbrt-v4's"),
)
# pbrt-v4's normal and bump maps, which a material gives (scene.cpp reads "normalmap" for every
# material, each Create GetFloatTextureOrNull("displacement")): from_pbrt maps them onto SURFACE's
PBRT_MAPS = (
    Parameter(None, "image", raw=True, pbrt="normalmap", doc="a normal map (pathtrace's normal_map, pbrt-v4's lookup)"),
    Parameter(None, "number", texture=True, pbrt="displacement",
              doc="a float texture of heights along the normal (pathtrace's bump_map); the normal map wins"),
)
OPACITY = next(p for p in SURFACE if p.name == "opacity")
DEFAULTS = {p.name: p.default for p in SURFACE}
MITSUBA_WRAPPERS = tuple(dict.fromkeys(p.mitsuba.partition(".")[0] for p in SURFACE if p.mitsuba))
FIELDS = {"Le": "emission", "emits_back": "emits_back", "twosided": "twosided", "opacity": "opacity",
          "normal_map": "normal_map", "bump_map": "bump_map", "perturbation": "perturbation"}


def from_pbrt(given: dict, warn) -> dict:
    """The SURFACE values of pbrt-v4's maps (PBRT_MAPS, by their names in `given`, None where
    absent); warn(name, text) tells what pathtrace leaves out.
    pbrt-v4's normalmap (an image read with a linear encoding, looked up bilinearly with repeat
    wrapping at (u, 1 - v), 2 rgb - 1 in the frame of dp/du and the shading normal:
    src/pbrt/materials.h, NormalMap) is pathtrace's normal map, the same frame and lookup (the
    pbrt reader's v is pbrt's 1 - v); its displacement, a float texture of heights along the
    shading normal (BumpMap: dp/du + dd/du n, the normal their cross product, on the geometric
    normal's side), pathtrace's bump map, whose slopes are the bitmap's analytic gradient where
    pbrt takes a finite difference over the pixel's footprint. Both perturb as pbrt-v4's do
    (Material.perturbation: the normal turned to the geometric normal's side, no
    shadow-terminator term: in tests/references/pbrt-v4's normalmap scene Mitsuba's term made the
    image 1.3 % darker than pbrt-v4's); pbrt-v4 evaluates the normal map where both are given."""
    image, displacement = given["normalmap"], given["displacement"]
    if image is not None:
        if displacement is not None:
            warn("displacement", "pbrt-v4 uses the normal map where a material has both; so does pathtrace, and "
                                 "the displacement is ignored")
        bitmap = TEXTURES["bitmap"].complete({"image": image, "wrap": "repeat", "filter": "bilinear"})
        return {"normal_map": Texture("bitmap", bitmap), "perturbation": "pbrt"}
    if isinstance(displacement, Texture):
        try:
            check_bump_map(displacement)
        except ValueError as e:
            warn("displacement", f"pathtrace cannot bump by this texture ({e}); the surface is rendered unbumped")
            return {}
        return {"bump_map": displacement, "perturbation": "pbrt"}
    if displacement is not None and displacement != 0:
        warn("displacement", "a constant displacement moves no normal; ignored")
    return {}


def dressed(material: Material, values: dict) -> Material:
    """material carrying the SURFACE values given (by their names), checked: each in its range,
    those with the BSDF and each other by table.surface_problem. Raises ValueError ("<name>:
    <problem>")."""
    maps = {"normal_map", "bump_map"} & set(values)
    # a value for a map there is none of is refused, but not its default, which a file may state
    if values.get("bump_scale", DEFAULTS["bump_scale"]) != DEFAULTS["bump_scale"] and "bump_map" not in values:
        raise ValueError("bump_scale: scales a bump_map, and there is none")
    if values.get("perturbation", DEFAULTS["perturbation"]) != DEFAULTS["perturbation"] and not maps:
        raise ValueError("perturbation: says how a normal_map or bump_map perturbs, and there is none")
    material = replace(material, **{FIELDS[k]: v for k, v in values.items() if k in FIELDS})
    error = out_of_range(SURFACE, values)
    if error:
        raise error
    problem = surface_problem(material)
    if problem:
        raise ValueError(": ".join(problem))
    if "bump_map" in values:
        try:
            material.bump_map = scaled_bump_map(values["bump_map"], values.get("bump_scale", 1.0))
        except ValueError as e:
            raise ValueError(f"bump_map: {e}") from None
    return material
