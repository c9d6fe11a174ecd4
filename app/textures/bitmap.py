"""The bitmap texture: an image file looked up at uv (Mitsuba 3's `bitmap`, pbrt-v4's
`imagemap`). 8-bit images stay 8 bits per channel on the device, decoded from sRGB in the kernel
unless marked raw (linear); 16-bit and HDR images are stored as half floats (float where a value
exceeds half's range)."""

import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError
from pathtrace.io.files import check_regular_file, shown
from pathtrace.parameters import Parameter
from pathtrace.textures.texture import KINDS, Texture, TextureType

# TEXELS_*, WRAP_* and FILTER_* of kernels/textures/bitmap.cl
SRGB8, LINEAR8, HALF, FLOAT = range(4)
WRAP_MODES = {"repeat": 0, "mirror": 1, "clamp": 2}
FILTERS = {"nearest": 0, "bilinear": 1}

LDR_FORMATS = (".png", ".jpg", ".jpeg", ".tga", ".bmp")
HDR_FORMATS = (".hdr", ".exr", ".pfm")
MAX_SIDE = 16384                  # texels on a side
MAX_FILE_BYTES = 2 << 30
HALF_MAX = 65504.0


def srgb_to_linear(c):
    """The sRGB transfer function's inverse (IEC 61966-2-1), on values in [0, 1]."""
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


SRGB_TABLE = srgb_to_linear(np.arange(256) / 255.0)


@dataclass(eq=False)
class Image:
    """A texture's image: texels (H, W, C) with C 1, 3 or 4; uint8 (sRGB-encoded unless
    `linear`) or float32 (linear)."""
    texels: np.ndarray
    linear: bool = False
    path: str = ""

    @property
    def size(self):
        return self.texels.shape[1], self.texels.shape[0]

    def linear_values(self) -> np.ndarray:
        """The texels as linear float64, rgb(a)."""
        if self.texels.dtype != np.uint8:
            return self.texels.astype(np.float64)
        return self.texels / 255.0 if self.linear else SRGB_TABLE[self.texels]

    def rgb(self) -> np.ndarray:
        v = self.linear_values()
        return np.repeat(v, 3, axis=2) if v.shape[2] == 1 else v[..., :3]

    @cached_property
    def summary(self) -> tuple:
        """The rgb's mean, least and greatest values per channel, which the host side asks for
        several times per texture (the material table's constants, the readers' range checks).
        Of 8-bit texels, from each channel's histogram through the (monotonic) decoding, without
        decoding every texel: the 401 maps of tori400-textured took 3 s of its loading that way."""
        t = self.texels[..., :3]
        if t.dtype != np.uint8:
            rgb = self.rgb().reshape(-1, 3)
            mean, low, high = rgb.mean(axis=0), rgb.min(axis=0), rgb.max(axis=0)
        else:
            table = np.arange(256) / 255.0 if self.linear else SRGB_TABLE
            counts = np.array([np.bincount(t[..., c].ravel(), minlength=256) for c in range(t.shape[2])])
            levels = [np.flatnonzero(h) for h in counts]
            mean = counts @ table / t[..., 0].size
            low, high = table[[k[0] for k in levels]], table[[k[-1] for k in levels]]
        return tuple(np.resize(x, 3) for x in (mean, low, high))


def read_image(path: Path, where: str, raw: bool = False, cache: dict = None) -> Image:
    """An image file as an Image: PNG, JPEG, TGA and BMP through Pillow (8-bit sRGB unless raw;
    16-bit decoded to float), HDR, EXR and PFM as linear float. Every problem is one line naming
    `where` and the file. A scene reader passes its `cache`, so that textures sharing a file
    share its Image (and its texels on the device)."""
    from pathtrace.io.images import read_hdr

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix and suffix not in LDR_FORMATS + HDR_FORMATS:
        raise UserError(f"{where}: '{shown(path)}': unknown image format '{path.suffix}' "
                        f"(use {', '.join(LDR_FORMATS + HDR_FORMATS)})")
    check_regular_file(path, where, "texture", MAX_FILE_BYTES)   # before realpath: a NUL byte; a folder
    if not suffix:
        raise UserError(f"{where}: '{shown(path)}': an image file's name needs its format's suffix "
                        f"({', '.join(LDR_FORMATS + HDR_FORMATS)})")
    if cache is not None:
        key = (os.path.realpath(path), raw)
        if key not in cache:
            cache[key] = read_image(path, where, raw)
        return cache[key]
    if suffix in HDR_FORMATS:
        texels = read_hdr(path, where, "texture", MAX_SIDE)
        return Image(np.ascontiguousarray(texels, np.float32), True, str(path))
    texels = _read_ldr(path, where)
    if texels.dtype != np.uint8 and not raw:
        texels = srgb_to_linear(texels).astype(np.float32)
    return Image(texels, raw or texels.dtype != np.uint8, str(path))


def _read_ldr(path: Path, where: str) -> np.ndarray:
    from PIL import Image as PILImage

    PILImage.MAX_IMAGE_PIXELS = None          # the side limit below applies instead
    try:
        with PILImage.open(path) as im:
            w, h = im.size
            if w > MAX_SIDE or h > MAX_SIDE:
                raise UserError(f"{where}: texture '{shown(path)}' is {w}x{h} texels; pathtrace takes "
                                f"at most {MAX_SIDE} on a side")
            if im.mode in ("I;16", "I;16B", "I;16L", "I"):
                return (np.asarray(im, np.float64)[..., None] / 65535.0).clip(0, 1).astype(np.float32)
            if im.mode == "F":
                return np.asarray(im, np.float32)[..., None]
            if im.mode not in ("L", "RGB", "RGBA"):
                im = im.convert("RGBA" if "A" in im.getbands() or "transparency" in im.info else "RGB")
            texels = np.asarray(im, np.uint8)
    except UserError:
        raise
    except Exception as e:        # Pillow raises anything on a truncated or malformed file
        raise UserError(f"{where}: texture '{shown(path)}' is not a readable {path.suffix[1:].upper()} image "
                        f"({type(e).__name__})") from None
    return texels[..., None] if texels.ndim == 2 else texels


PBRT_ENCODING = "sRGB for a PNG, else linear"      # pbrt-v4's default (SpectrumImageTexture::Create)


def _pbrt_linear(encoding, given) -> bool:
    """pbrt-v4's `encoding`: whether 8-bit values are linear; `gamma g` decodes as sRGB
    (from_pbrt warns)."""
    if encoding == PBRT_ENCODING:
        encoding = "sRGB" if str(given["filename"]).lower().endswith(".png") else "linear"
    if encoding not in ("sRGB", "linear") and not encoding.startswith("gamma "):
        raise ValueError(f"'encoding' must be sRGB, linear or gamma <g>, got {encoding!r}")
    return encoding == "linear"


def _pbrt_filter(name, given) -> str:
    """pbrt-v4's filters: point is nearest, the others (trilinear, ewa) bilinear."""
    if name not in ("point", "bilinear", "trilinear", "ewa"):
        raise ValueError(f"'filter' must be point, bilinear, trilinear or ewa, got {name!r}")
    return "nearest" if name == "point" else "bilinear"


def _pbrt_wrap(wrap, given) -> str:
    """pbrt-v4's wraps: black and octahedralsphere clamp (from_pbrt warns)."""
    if wrap not in ("repeat", "clamp", "black", "octahedralsphere"):
        raise ValueError(f"'wrap' must be repeat, black, clamp or octahedralsphere, got {wrap!r}")
    return "repeat" if wrap == "repeat" else "clamp"


def inverted(image: Image, scale: float) -> Image:
    """pbrt-v4's imagemap `invert` (src/pbrt/textures.cpp, SpectrumImageTexture::Evaluate:
    rgb = scale * lookup, then ClampZero(1 - rgb) per channel; FloatImageTexture::Evaluate:
    max(0, 1 - v)): applied to the texels, in linear float, which bilinear filtering then
    interpolates as pbrt interpolates before inverting (the two differ only next to texels that
    the clamp at zero cuts). An alpha channel is kept."""
    values = image.linear_values()
    rgb = np.maximum(1.0 - scale * values[..., :3], 0.0)
    texels = np.concatenate([rgb, values[..., 3:]], axis=2) if values.shape[2] == 4 else rgb
    # made in memory: no file holds these texels (convert writes them out: app/cli/convert.py)
    return Image(np.ascontiguousarray(texels, np.float32), True)


class Bitmap(TextureType):
    name = "bitmap"
    doc = ("an image file (PNG, JPEG, TGA, BMP: 8-bit sRGB unless raw; HDR, EXR, PFM: linear), "
           "with wrap mode repeat, mirror or clamp and filter bilinear or nearest")
    formats = {"mitsuba": "bitmap", "pbrt": "imagemap"}
    parameters = (
        Parameter("file", "image", doc="the image file, relative to the scene file", mitsuba="filename",
                  pbrt="filename"),
        Parameter("raw", "bool", False, doc="8-bit values taken as linear, not sRGB", mitsuba="raw",
                  pbrt="encoding", pbrt_kind="string", pbrt_default=PBRT_ENCODING, from_pbrt=_pbrt_linear),
        Parameter("filter", "name", "bilinear", choices=tuple(FILTERS), doc="the lookup", mitsuba="filter_type",
                  pbrt="filter", pbrt_default="bilinear", from_pbrt=_pbrt_filter),
        Parameter("wrap", "name", "repeat", choices=tuple(WRAP_MODES), doc="beyond [0, 1]", mitsuba="wrap_mode",
                  pbrt="wrap", pbrt_default="repeat", from_pbrt=_pbrt_wrap))
    format_only = (Parameter(None, "number", pbrt="scale", pbrt_default=1.0, doc="a factor on the texels"),
                   Parameter(None, "bool", pbrt="invert", pbrt_default=False, doc="max(0, 1 - scale texel)"))
    pbrt_uv = 1.0
    # repeat wrap: a bilinear lookup's mean over the unit square is then its texels' mean
    examples = ({"image": Image(np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255]],
                                          [[255, 255, 255], [128, 64, 32], [0, 0, 0]]], np.uint8))},
                {"image": Image(np.array([[[0.5], [3.0]], [[40.0], [0.0]]], np.float32), linear=True),
                 "filter": "nearest", "wrap": "mirror"},
                {"image": Image(np.array([[[10, 200, 30, 255], [90, 0, 250, 128]]], np.uint8), linear=True)})

    def complete(self, params):
        values = super().complete(params)
        values.pop("raw")                           # the reader read the file so (Image.linear)
        if "file" in values:
            values["image"] = values.pop("file")
        if not isinstance(values.get("image"), Image):
            raise ValueError("file: missing (a bitmap needs an image file)")
        for key, choices in (("wrap", WRAP_MODES), ("filter", FILTERS)):
            if values[key] not in choices:
                raise ValueError(f"{key}: unknown {key} {values[key]!r} (known: {', '.join(choices)})")
        values["image"] = check_texels(values["image"])
        return values

    def from_pbrt(self, values, given, warn):
        """pbrt-v4's imagemap: its image, times `scale` (a scale texture over it), or inverted."""
        if given["encoding"].startswith("gamma "):
            warn(f"pathtrace decodes 8-bit images as sRGB or linear; {given['encoding']} is taken as sRGB")
        if given["wrap"] in ("black", "octahedralsphere"):
            warn(f"pathtrace has no {given['wrap']} wrap; it clamps")
        scale = given["scale"]
        if given["invert"]:
            values["file"], scale = inverted(values["file"], scale), 1.0
        texture = Texture(self.name, self.complete(values))
        return texture if scale == 1.0 else Texture("scale", KINDS["scale"].complete({"tex": texture, "scale": scale}))

    def pack(self, texture, row, texels):
        image = texture.params["image"]
        data = image.texels
        if data.dtype == np.uint8:
            fmt = LINEAR8 if image.linear else SRGB8
        elif np.max(data, initial=0.0) <= HALF_MAX:
            fmt, data = HALF, data.astype(np.float16)
        else:
            fmt = FLOAT
        if data.shape[2] == 3:      # one aligned load per texel (kernels/textures/bitmap.cl)
            data = np.concatenate([data, np.zeros_like(data[..., :1])], axis=2)
        row["width"], row["height"] = image.size
        row["channels"] = data.shape[2]
        row["format"] = fmt
        row["wrap"] = WRAP_MODES[texture.params["wrap"]]
        row["filter"] = FILTERS[texture.params["filter"]]
        row["texels"] = texels.add(image, data)

    def mean(self, texture):
        return texture.params["image"].summary[0]

    def bounds(self, texture):
        return texture.params["image"].summary[1:]


def check_texels(image: Image) -> Image:
    """Refuses (ValueError) an image whose texels are not finite and non-negative, or whose
    channels are not 1, 3 or 4 (2 channels, grey and alpha, keep the grey)."""
    t = image.texels
    if t.ndim != 3 or t.shape[0] == 0 or t.shape[1] == 0:
        raise ValueError(f"'{shown(image.path)}' has no texels")
    if t.shape[2] == 2:
        image = Image(np.ascontiguousarray(t[..., :1]), image.linear, image.path)
    elif t.shape[2] not in (1, 3, 4):
        raise ValueError(f"'{shown(image.path)}' has {t.shape[2]} channels; textures have 1, 3 or 4")
    if image.texels.dtype != np.uint8 and not (np.all(np.isfinite(image.texels)) and image.texels.min() >= 0):
        raise ValueError(f"'{shown(image.path)}' holds negative, NaN or infinite texels")
    return image
