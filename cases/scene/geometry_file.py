"""A scene's projectile read from a file: the CAD or mesh file, its unit, axis, materials' field and symmetry."""

from __future__ import annotations

import math
from typing import Literal, Self

from pydantic import TypeAdapter, ValidationError, field_validator, model_validator

from mesh.imported import CAD_SUFFIXES, file_digest

from .base import Label, Number, Strict, field

__all__ = ["GeometryFileSpec", "MESH_SUFFIXES"]

_DIRECTION = TypeAdapter(tuple[Number, Number, Number])

MESH_SUFFIXES = (
    ".msh",
    ".vtu",
    ".vtk",
    ".inp",
    ".med",
    ".xdmf",
    ".xmf",
    ".mesh",
    ".meshb",
    ".bdf",
    ".nas",
    ".h5m",
    ".e",
    ".exo",
    ".vol",
    ".ugrid",
    ".su2",
    ".avs",
    ".f3grid",
    ".mdpa",
    ".dat",
    ".tec",
)


class GeometryFileSpec(Strict):
    """A projectile read from a file: a CAD solid (STEP, BREP, IGES) that gmsh meshes, or a volume mesh of
    tetrahedra that meshio reads.  A path relative to the scene file is found beside it."""

    file: Label = field(description="the CAD or mesh file")
    unit: Literal["m", "cm", "mm", "in"] = field("m", description="what a length of 1 in the file means")
    axis: tuple[Number, Number, Number] | Literal["auto"] | None = field(
        None,
        description="the file's direction from tail to tip, through the body's centroid wherever the file puts it;"
        ' "auto": the axis of least inertia, tip at the end further from the centroid; default +x, refused'
        " when the body's long axis or tip lie elsewhere (docs/geometry.md)",
    )
    cell_field: Label | None = field(
        None, description="a mesh's cell-data field that names the materials (default: the physical groups)"
    )
    symmetry: Literal["auto", "none", "mirror_y", "mirror_z", "mirrors", "revolution"] = field(
        "auto",
        description="the mirror planes a CAD body is meshed by (on one side, then mirrored): those it has"
        " (auto), none, or declared and checked: y = 0 (mirror_y), z = 0 (mirror_z), both (mirrors,"
        " revolution); docs/geometry.md",
    )
    sha256: Label | None = field(
        None,
        description="the file's digest: filled in when the scene is read; a changed"
        " file is refused by a resolved scene that holds the old one",
    )

    @field_validator("axis", mode="before")
    @classmethod
    def _one_axis(cls, value: object) -> object:
        """One line for a bad axis (not one per member of the union)."""
        if value is None or value == "auto":
            return value
        if isinstance(value, str) or not isinstance(value, (list, tuple)) or len(value) != 3:
            raise ValueError('must be "auto" or a direction [x, y, z] from tail to tip')
        try:
            return _DIRECTION.validate_python(value)
        except ValidationError as exc:
            raise ValueError(f'must be "auto" or three numbers ({exc.errors()[0]["msg"].lower()})') from None

    @model_validator(mode="after")
    def _readable(self) -> Self:
        from pathlib import Path

        path = Path(self.file)
        suffix = path.suffix.lower()
        if suffix not in CAD_SUFFIXES and suffix not in MESH_SUFFIXES:
            raise ValueError(
                f"file = {self.file!r}: not a CAD or mesh file (allowed suffixes: CAD"
                f" {', '.join(sorted(CAD_SUFFIXES))}; volume meshes {', '.join(MESH_SUFFIXES)})"
            )
        if suffix not in CAD_SUFFIXES and self.symmetry not in ("auto", "none"):
            raise ValueError(
                f"symmetry = {self.symmetry!r}: a mesh file is used as its elements are; mirror planes apply to"
                f' CAD files ({", ".join(sorted(CAD_SUFFIXES))}): say symmetry = "none" or give the CAD file'
            )
        if suffix in CAD_SUFFIXES and self.cell_field is not None:
            raise ValueError(
                "cell_field names the materials of a mesh file: drop it for a CAD file (its solids have names)"
            )
        try:
            digest = file_digest(path)
        except OSError as exc:
            raise ValueError(
                f"file = {self.file!r}: cannot read it ({exc.strerror or exc}); give"
                " a readable file, absolute or relative to the scene file's folder"
            ) from None
        if self.sha256 is not None and self.sha256 != digest:
            raise ValueError(
                f"file = {self.file!r}: changed since this scene was resolved (sha256 {digest[:12]}...,"
                f" the scene holds {self.sha256[:12]}...); drop sha256 to use the file as it is now"
            )
        if isinstance(self.axis, tuple) and (not any(self.axis) or math.hypot(*self.axis) < 1e-12):
            raise ValueError(f"axis = {list(self.axis)}: must be a non-zero direction")
        self.sha256 = digest
        return self

    @property
    def is_cad(self) -> bool:
        from pathlib import Path

        return Path(self.file).suffix.lower() in CAD_SUFFIXES
