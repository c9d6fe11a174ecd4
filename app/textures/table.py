"""A scene's textures compiled into the tables the kernels read: TEXTURE rows, the texels of
their images in one byte buffer, and the TEXTURE_BINDING rows that say which material
parameters they give."""

from dataclasses import dataclass

import numpy as np

from pathtrace.textures.bitmap import SRGB_TABLE
from pathtrace.textures.registry import TAGS, TEXTURES
from pathtrace.textures.texture import Texture
from pathtrace.types import TEXTURE, TEXTURE_BINDING


OPACITY_SLOT = 16        # kernels/masks.cl: SLOT_OPACITY
NORMAL_MAP_SLOTS = (20, 24)   # kernels/normal_maps.cl: SLOT_NORMAL_MAP, SLOT_BUMP_MAP


class TexelStore:
    """The texel buffer being filled: the sRGB decoding table (256 float32, which
    kernels/textures/bitmap.cl reads), then each image 16-byte aligned, an image that several
    textures share stored once."""

    def __init__(self):
        table = SRGB_TABLE.astype(np.float32).view(np.uint8)
        self.parts, self.words, self.at = [table], len(table) // 4, {}

    def add(self, key, data: np.ndarray) -> int:
        """Stores `data` (once per key); returns its first 4-byte word."""
        if id(key) not in self.at:
            # aligned to 16 bytes, so that a texel of four floats is one aligned load
            raw = np.ascontiguousarray(data).view(np.uint8).reshape(-1)
            raw = np.concatenate([raw, np.zeros(-len(raw) % 16, np.uint8)])
            self.at[id(key)] = self.words
            self.parts.append(raw)
            self.words += len(raw) // 4
        return self.at[id(key)]

    def buffer(self) -> np.ndarray:
        return np.concatenate(self.parts)


@dataclass
class TextureTables:
    textures: np.ndarray       # TEXTURE rows
    texels: np.ndarray         # uint8
    bindings: np.ndarray       # TEXTURE_BINDING rows
    first: np.ndarray          # per material row: its first binding, or -1
    types: tuple               # the texture types used (pathtrace.features.Features.textures)
    masks: bool                # a binding is an opacity (Features.masks)
    normal_maps: bool          # a binding is a normal or bump map (Features.normal_maps)


def compile_textures(bindings: list) -> TextureTables:
    """bindings: per material row, a list of (slot, width, Texture). Raises ValueError for a
    texture that reads a texture which itself combines others (inputs nest one level deep)."""
    rows, order = {}, []

    def row_of(texture: Texture) -> int:
        if id(texture) not in rows:
            rows[id(texture)] = len(order)
            order.append(texture)
        return rows[id(texture)]

    table, first = [], np.full(len(bindings), -1, np.int32)
    for material, entries in enumerate(bindings):
        if entries:
            first[material] = len(table)
        for k, (slot, width, texture) in enumerate(entries):
            table.append((row_of(texture), slot, width, int(k == len(entries) - 1)))
    for texture in list(order):          # grows as inputs are found; they are leaves
        for child in texture.inputs():
            if not child.kind.leaf:
                raise ValueError(f"texture {texture.name or texture.type}: its input "
                                 f"{child.name or child.type} combines other textures; inputs "
                                 "nest one level deep")
            row_of(child)
    store = TexelStore()
    textures = np.zeros(len(order), TEXTURE)
    for row, texture in zip(textures, order):
        kind = TEXTURES[texture.type]
        m = texture.params.get("to_uv", np.eye(3))
        row["to_u"][:3], row["to_v"][:3] = m[0], m[1]
        row["type"] = TAGS[texture.type]
        row["input"] = -1
        for k, name in enumerate(kind.inputs):
            value = texture.params[name]
            if isinstance(value, Texture):
                row["input"][k] = rows[id(value)]
            else:
                row["value"][k, :3] = value
        kind.pack(texture, row, store)
    return TextureTables(textures if len(textures) else np.zeros(1, TEXTURE), store.buffer(),
                         np.array(table, TEXTURE_BINDING) if table else np.zeros(1, TEXTURE_BINDING),
                         first, tuple(n for n in TEXTURES if any(t.type == n for t in order)),
                         any(slot == OPACITY_SLOT for _, slot, _, _ in table),
                         any(slot in NORMAL_MAP_SLOTS for _, slot, _, _ in table))
