"""Lights: the delta lights a scene names (point, spot, directional), the light types' registry
and the table next-event estimation chooses lights from."""

from pathtrace.lights.directional import DirectionalLight
from pathtrace.lights.light import DeltaLight
from pathtrace.lights.point import PointLight
from pathtrace.lights.registry import DELTA_LIGHTS, LIGHTS, TAGS, kernel_parts
from pathtrace.lights.spot import SpotLight
from pathtrace.lights.table import (LightPlan, LightTable, alias_table, build_light_table, emitted_power,
                                    keep_threshold, light_plan)
from pathtrace.lights.tree import primitive_bounds

__all__ = ["DELTA_LIGHTS", "LIGHTS", "TAGS", "DeltaLight", "DirectionalLight", "LightPlan", "LightTable",
           "PointLight", "SpotLight", "alias_table", "build_light_table", "emitted_power", "keep_threshold",
           "kernel_parts", "light_plan", "primitive_bounds"]
