"""Analytic shapes (app/shapes/shape.py): kinds registered in app/shapes/registry.py."""

from pathtrace.shapes.registry import SHAPES, TAGS, dispatch_source, kernel_files
from pathtrace.shapes.shape import ROWS, Shape, ShapeKind

__all__ = ["SHAPES", "TAGS", "ROWS", "Shape", "ShapeKind", "dispatch_source", "kernel_files"]
