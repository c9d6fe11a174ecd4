"""Analytic shapes (app/shapes/shape.py): kinds registered in app/shapes/registry.py."""

from pathtrace.shapes.registry import SHAPES, TAGS, dispatch_source, kernel_files
from pathtrace.shapes.shape import ROWS, Shape, ShapeKind
from pathtrace.shapes.texture_uv import TextureUV, texture_uv_source

__all__ = ["SHAPES", "TAGS", "ROWS", "Shape", "ShapeKind", "TextureUV", "dispatch_source", "kernel_files",
           "texture_uv_source"]
