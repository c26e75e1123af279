"""Import a user mesh (STL/OBJ/PLY) as a grasp object with the set-up of a shipped one."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

import viser

from app.errors import HandbenchError
from app.model.objects import MESH_EXTENSIONS, OBJECT_KEYS, import_object


class ImportPanel:
    """'like' object, units, and an upload button; calls ``on_imported(key)``."""

    def __init__(self, gui: viser.GuiApi, on_imported: Callable[[str], None]) -> None:
        self._on_imported = on_imported
        like_opts: tuple[str, ...] = OBJECT_KEYS
        self.like = gui.add_dropdown("Grasp like", options=like_opts, initial_value="chips_can")
        unit_opts: tuple[str, ...] = ("mm", "m")
        self.units = gui.add_dropdown("File units", options=unit_opts, initial_value="mm")
        self.upload = gui.add_upload_button("Import STL/OBJ/PLY", icon=viser.Icon.UPLOAD)
        gui.add_markdown(
            "<small>The mesh takes the grasp set-up (target, cone, rolls) of 'Grasp like'. "
            "Object frame as in the file; +z up, origin at the base centre works best.</small>"
        )
        self.status = gui.add_markdown("")
        self.upload.on_upload(lambda _: self._uploaded())

    def _uploaded(self) -> None:
        f = self.upload.value
        suffix = Path(f.name).suffix.lower()
        if suffix not in MESH_EXTENSIONS:
            self.status.content = f"`{f.name}`: choose one of {', '.join(MESH_EXTENSIONS)}"
            return
        with tempfile.TemporaryDirectory(prefix="handbench-import-") as d:
            path = Path(d) / Path(f.name).name
            path.write_bytes(f.content)
            try:
                obj = import_object(path, like=self.like.value, units=self.units.value)
            except HandbenchError as e:
                self.status.content = f"import failed: {e}"
                return
        self.status.content = f"imported **{obj.key}** ({len(obj.mesh.faces)} faces)"
        self._on_imported(obj.key)
