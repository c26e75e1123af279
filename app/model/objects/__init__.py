"""The grasp objects: data files ``objects/*.toml``, meshes, SDFs and FCL collision pieces.

Object frame: stated in each data file (origin at the base centre of the object resting on
a table, +z up). Lengths in mm everywhere; angles in degrees in files, radians inside.
"""

from app.model.objects.importer import MESH_EXTENSIONS, import_object, read_mesh
from app.model.objects.model import (
    GraspObject,
    available_keys,
    load_object,
    register_object,
    unregister_object,
)
from app.model.objects.spec import OBJECT_KEYS, GraspSetup, ObjectFileError, ObjectSpec

__all__ = [
    "MESH_EXTENSIONS",
    "OBJECT_KEYS",
    "GraspObject",
    "GraspSetup",
    "ObjectFileError",
    "ObjectSpec",
    "available_keys",
    "import_object",
    "load_object",
    "read_mesh",
    "register_object",
    "unregister_object",
]
