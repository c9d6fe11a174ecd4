"""Materials: the BSDF types (one module per family, one kernel file per type in
kernels/bsdfs/), their registry and the scene's material table."""

from pathtrace.materials.bsdf import DELTA, EMITS_BACK, NULL, TRANSMISSIVE, TWOSIDED, BSDFType, Param
from pathtrace.materials.registry import BSDFS, TAGS, dispatch_source, kernel_files, tag_source
from pathtrace.materials.table import Material, MaterialTable, pack

__all__ = ["BSDFS", "TAGS", "DELTA", "EMITS_BACK", "NULL", "TRANSMISSIVE", "TWOSIDED", "BSDFType", "Param", "Material",
           "MaterialTable", "dispatch_source", "kernel_files", "pack", "tag_source"]
