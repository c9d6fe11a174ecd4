"""A scene's textures compiled into the tables the kernels read: TEXTURE rows, the texels of
their images in one byte buffer, and the TEXTURE_BINDING rows that say which material
parameters they give."""

from dataclasses import dataclass

import numpy as np

from pathtrace.textures.bitmap import SRGB_TABLE
from pathtrace.textures.registry import TAGS, TEXTURE_REGISTERS, TEXTURES
from pathtrace.textures.texture import Texture
from pathtrace.device.types import TEXTURE, TEXTURE_BINDING


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
    types: tuple               # the texture types used (pathtrace.device.features.Features.textures)
    masks: bool                # a binding is an opacity (Features.masks)
    normal_maps: bool          # a binding is a normal or bump map (Features.normal_maps)


def combining_inputs(texture: Texture) -> list:
    """(k, input) of the inputs of `texture` that combine other textures."""
    return [(k, texture.params[n]) for k, n in enumerate(texture.kind.inputs)
            if isinstance(texture.params.get(n), Texture) and not texture.params[n].kind.leaf]


def registers_needed(root: Texture) -> dict:
    """id -> the registers the program of each combining texture under `root` needs (Sethi and
    Ullman: its combining inputs evaluated in decreasing need, the i-th of them holding i values
    below it), computed without recursion: chains may be thousands long."""
    need, stack = {}, [(root, False)]
    while stack:
        node, inputs_done = stack.pop()
        if id(node) in need:
            continue
        inputs = [t for _, t in combining_inputs(node)]
        if inputs_done:
            needs = sorted((need[id(t)] for t in inputs), reverse=True)
            need[id(node)] = max([1] + [n + i for i, n in enumerate(needs)])
        else:
            stack.append((node, True))
            stack += [(t, False) for t in inputs if id(t) not in need]
    return need


def program(root: Texture) -> list:
    """The steps of a combining texture's program (kernels/texture.cl): (texture, {input k:
    register}) for each combining texture of its tree in post-order, `root` last; each pushes
    its value after its combining inputs' are popped. Raises ValueError where the tree needs
    more than TEXTURE_REGISTERS."""
    need = registers_needed(root)
    if need[id(root)] > TEXTURE_REGISTERS:
        raise ValueError(f"texture {root.name or root.type}: its tree of combined textures needs "
                         f"{need[id(root)]} registers to evaluate, more than the kernels' {TEXTURE_REGISTERS} "
                         "(a balanced tree of more than 2^7 textures that each combine two)")

    def order(node):
        return sorted(combining_inputs(node), key=lambda kt: -need[id(kt[1])])
    steps, top = [], 0
    frames = [[root, order(root), 0, {}, None]]       # node, its inputs in order, next, registers, its k
    while frames:
        frame = frames[-1]
        node, inputs, at, registers, _ = frame
        if at < len(inputs):
            frame[2] += 1
            k, child = inputs[at]
            frames.append([child, order(child), 0, {}, k])
            continue
        frames.pop()
        top -= len(inputs)
        steps.append((node, registers))
        if frames:
            frames[-1][3][frame[4]] = top
        top += 1
    return steps


def compile_textures(bindings: list) -> TextureTables:
    """bindings: per material row, a list of (parameter name, slot, width, Texture), as
    MaterialTable.textures holds them (the name is not compiled). A texture that combines none
    is a row; one that combines others, the last row of its program (its tree's combining
    textures, kernels/texture.cl), which a tree shared by several materials shares. Raises
    ValueError for a tree that needs more registers than the kernels have."""
    order, leaves, roots = [], {}, {}       # rows: (texture, registers or None, first step or -1)

    def leaf_row(texture: Texture) -> int:
        if id(texture) not in leaves:
            leaves[id(texture)] = len(order)
            order.append((texture, None, -1))
        return leaves[id(texture)]

    def row_of(texture: Texture) -> int:
        if texture.kind.leaf:
            return leaf_row(texture)
        if id(texture) not in roots:
            first = len(order)
            order.extend((node, registers, first) for node, registers in program(texture))
            roots[id(texture)] = len(order) - 1
        return roots[id(texture)]

    table, first = [], np.full(len(bindings), -1, np.int32)
    for material, entries in enumerate(bindings):
        if entries:
            first[material] = len(table)
        for k, (_, slot, width, texture) in enumerate(entries):
            table.append((row_of(texture), slot, width, int(k == len(entries) - 1)))
    for texture, registers, _ in list(order):
        if registers is not None:
            for name in texture.kind.inputs:
                value = texture.params[name]
                if isinstance(value, Texture) and value.kind.leaf:
                    leaf_row(value)
    store = TexelStore()
    textures = np.zeros(len(order), TEXTURE)
    for row, (texture, registers, start) in zip(textures, order):
        kind = TEXTURES[texture.type]
        m = texture.params.get("to_uv", np.eye(3))
        row["to_u"][:3], row["to_v"][:3] = m[0], m[1]
        row["type"] = TAGS[texture.type]
        row["input"] = -1
        row["program"] = start
        for k, name in enumerate(kind.inputs):
            value = texture.params[name]
            if not isinstance(value, Texture):
                row["value"][k, :3] = value
            else:
                row["input"][k] = leaves[id(value)] if value.kind.leaf else -2 - registers[k]
        kind.pack(texture, row, store)
    normal_maps = any(slot in NORMAL_MAP_SLOTS for _, slot, _, _ in table)
    # kernels/normal_maps.cl reads a bump map's slopes from a bitmap, whatever its normal map is
    types = tuple(n for n in TEXTURES if any(t.type == n for t, _, _ in order) or (normal_maps and n == "bitmap"))
    return TextureTables(textures if len(textures) else np.zeros(1, TEXTURE), store.buffer(),
                         np.array(table, TEXTURE_BINDING) if table else np.zeros(1, TEXTURE_BINDING),
                         first, types, any(slot == OPACITY_SLOT for _, slot, _, _ in table), normal_maps)
