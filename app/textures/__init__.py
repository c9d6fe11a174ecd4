"""Textures: the texture types (one module each, one kernel file each in kernels/textures/),
their registry, and the scene's texture tables."""

from pathtrace.textures.bitmap import Image, read_image
from pathtrace.textures.registry import TAGS, TEXTURES, kernel_parts
from pathtrace.textures.table import TextureTables, compile_textures
from pathtrace.textures.texture import Texture, TextureType

__all__ = ["Image", "TAGS", "TEXTURES", "Texture", "TextureTables", "TextureType", "compile_textures",
           "kernel_parts", "read_image"]
