"""Labels as typed objects: what `purkinje truth` and `purkinje render`
write (docs/labels.md), with the same field names and units.

A value that does not exist for a feature's status (a glint behind the
camera has no pixel) is None here, as it is null in the files. The array
views (``View.glints_px``, ``PupilLabel.border_px``) are numpy masked
arrays: such values are masked, never NaN.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Union

import numpy as np


def _vector(value: Optional[List[float]]) -> Optional[np.ndarray]:
    return None if value is None else np.asarray(value, dtype=float)


def _pixels(points: List[Any]) -> np.ma.MaskedArray:
    """(n, 2) pixels of objects with u_px and v_px, None masked."""
    data = np.zeros((len(points), 2))
    mask = np.zeros((len(points), 2), dtype=bool)
    for i, p in enumerate(points):
        if p.u_px is None or p.v_px is None:
            mask[i] = True
        else:
            data[i] = (p.u_px, p.v_px)
    return np.ma.MaskedArray(data, mask=mask)


@dataclass(frozen=True)
class Projection:
    """A point's image: status ("ok", "outside_image", "behind_camera") and pixel."""

    status: str
    u_px: Optional[float]
    v_px: Optional[float]

    @property
    def pixel_px(self) -> Optional[np.ndarray]:
        """(u, v), or None behind the camera."""
        return None if self.u_px is None else np.array([self.u_px, self.v_px])

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "Projection":
        return cls(d["status"], d["u_px"], d["v_px"])


@dataclass(frozen=True)
class Ellipse:
    """An ellipse in the image, px; angle_deg of semi-axis 1 from +u toward +v."""

    center_u_px: float
    center_v_px: float
    semi_axis_1_px: float
    semi_axis_2_px: float
    angle_deg: float

    @property
    def center_px(self) -> np.ndarray:
        """(u, v)"""
        return np.array([self.center_u_px, self.center_v_px])

    @classmethod
    def _from(cls, d: Optional[Dict[str, Any]]) -> Optional["Ellipse"]:
        if d is None:
            return None
        return cls(d["center_u_px"], d["center_v_px"], d["semi_axis_1_px"], d["semi_axis_2_px"], d["angle_deg"])


@dataclass(frozen=True)
class GlintLabel:
    """The first Purkinje image of one light (docs/labels.md, views[k].glints[j])."""

    illuminator: int
    illuminator_name: str
    status: str
    u_px: Optional[float]
    v_px: Optional[float]
    point_mm: Optional[np.ndarray]
    normal: Optional[np.ndarray]
    incident: Optional[np.ndarray]
    reflected: Optional[np.ndarray]
    incidence_deg: Optional[float]
    on_cap: Optional[bool]
    #: For status "occluded": "skin", "lash", "brow", "mesh" or "eye" (what the camera sees in front, else what shadows it).
    occluded_by: Optional[str] = None

    @property
    def pixel_px(self) -> Optional[np.ndarray]:
        """(u, v), or None where the path has no pixel"""
        return None if self.u_px is None else np.array([self.u_px, self.v_px])

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "GlintLabel":
        return cls(d["illuminator"], d["illuminator_name"], d["status"], d["u_px"], d["v_px"],
                   _vector(d["point_mm"]), _vector(d["normal"]), _vector(d["incident"]), _vector(d["reflected"]),
                   d["incidence_deg"], d["on_cap"], d.get("occluded_by"))


@dataclass(frozen=True)
class DistractorLabel:
    """A highlight that is no Purkinje image (docs/labels.md, views[k].distractors[j]):
    kind "sclera", one light mirrored by a wet sclera's tear film,
    "tear_meniscus" and "upper_tear_meniscus", by the lower and the upper
    lid's tear meniscus (render labels only), or "spectacle_lens_front" /
    "spectacle_lens_back", by a glasses lens's surface (a ghost;
    spectacle_lens names the lens)."""

    kind: str
    illuminator: int
    illuminator_name: str
    status: str
    u_px: Optional[float]
    v_px: Optional[float]
    point_mm: np.ndarray
    normal: np.ndarray
    incidence_deg: float
    #: For status "occluded": "skin", "lash", "brow", "mesh" or "eye" (the cornea included).
    occluded_by: Optional[str] = None
    #: For a ghost: the lens's index in the scene's spectacle_lenses, and its name.
    spectacle_lens: Optional[int] = None
    spectacle_lens_name: Optional[str] = None

    @property
    def pixel_px(self) -> Optional[np.ndarray]:
        """(u, v), or None where it has no pixel"""
        return None if self.u_px is None else np.array([self.u_px, self.v_px])

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "DistractorLabel":
        return cls(d["kind"], d["illuminator"], d["illuminator_name"], d["status"], d["u_px"], d["v_px"],
                   _vector(d["point_mm"]), _vector(d["normal"]), d["incidence_deg"], d.get("occluded_by"),
                   d.get("spectacle_lens"), d.get("spectacle_lens_name"))


@dataclass(frozen=True)
class RefractedPoint:
    """A point inside the eye seen through the cornea: a pupil-border point
    (index and angle_deg given) or the refracted pupil centre (both None)."""

    index: Optional[int]
    angle_deg: Optional[float]
    status: str
    u_px: Optional[float]
    v_px: Optional[float]
    border_point_mm: Optional[np.ndarray]
    cornea_point_mm: Optional[np.ndarray]
    posterior_point_mm: Optional[np.ndarray]
    cornea_normal: Optional[np.ndarray]
    inner_direction: Optional[np.ndarray]
    outer_direction: Optional[np.ndarray]
    on_cap: Optional[bool]
    #: For status "occluded": "skin", "lash", "brow", "mesh" or "eye" (what the camera sees in front of it).
    occluded_by: Optional[str] = None

    @property
    def pixel_px(self) -> Optional[np.ndarray]:
        """(u, v), or None where the path has no pixel"""
        return None if self.u_px is None else np.array([self.u_px, self.v_px])

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "RefractedPoint":
        return cls(d.get("index"), d.get("angle_deg"), d["status"], d["u_px"], d["v_px"],
                   _vector(d.get("border_point_mm")), _vector(d.get("cornea_point_mm")),
                   _vector(d.get("posterior_point_mm")), _vector(d.get("cornea_normal")),
                   _vector(d.get("inner_direction")), _vector(d.get("outer_direction")), d.get("on_cap"),
                   d.get("occluded_by"))


@dataclass(frozen=True)
class PupilLabel:
    """The pupil seen through the cornea (docs/labels.md, views[k].pupil)."""

    border: List[RefractedPoint]
    ellipse: Optional[Ellipse]
    visible_ellipse: Optional[Ellipse]
    refracted_center: RefractedPoint
    unrefracted_center: Projection

    @property
    def border_px(self) -> np.ma.MaskedArray:
        """(n, 2) border pixels; masked where a point has none."""
        return _pixels(self.border)

    @property
    def border_status(self) -> List[str]:
        """Each border point's status, in order."""
        return [p.status for p in self.border]

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "PupilLabel":
        return cls([RefractedPoint._from(p) for p in d["border"]], Ellipse._from(d["ellipse"]),
                   Ellipse._from(d.get("visible_ellipse")), RefractedPoint._from(d["refracted_center"]),
                   Projection._from(d["unrefracted_center"]))


@dataclass(frozen=True)
class View:
    """One camera looking at one eye."""

    camera: int
    camera_name: str
    eye: int
    cornea_center: Projection
    rotation_center: Projection
    glints: List[GlintLabel]
    pupil: PupilLabel
    #: A wet eye's highlights on its tears (empty for a dry eye).
    distractors: List[DistractorLabel] = field(default_factory=list)

    @property
    def glints_px(self) -> np.ma.MaskedArray:
        """(lights, 2) glint pixels in light order; masked where a glint has none."""
        return _pixels(self.glints)

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "View":
        return cls(d["camera"], d["camera_name"], d["eye"], Projection._from(d["cornea_center"]),
                   Projection._from(d["rotation_center"]), [GlintLabel._from(g) for g in d["glints"]],
                   PupilLabel._from(d["pupil"]), [DistractorLabel._from(x) for x in d.get("distractors", [])])


@dataclass(frozen=True)
class EyeLabel:
    """An eye's 3D truth (docs/labels.md, eyes[i]); the rest is in `raw`."""

    index: int
    model: str
    cornea_center_mm: np.ndarray
    rotation_center_mm: np.ndarray
    pupil_center_mm: np.ndarray
    corneal_apex_mm: np.ndarray
    optical_axis: np.ndarray
    visual_axis: np.ndarray
    cornea_radius_mm: float
    pupil_radius_mm: float
    raw: Dict[str, Any] = field(repr=False)

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "EyeLabel":
        return cls(d["index"], d["model"], _vector(d["cornea_center_mm"]), _vector(d["rotation_center_mm"]),
                   _vector(d["pupil_center_mm"]), _vector(d["corneal_apex_mm"]), _vector(d["optical_axis"]),
                   _vector(d["visual_axis"]), d["cornea_radius_mm"], d["pupil_radius_mm"], d)


@dataclass(frozen=True)
class Labels:
    """A labels file's content: the scene's cameras, lights and eyes, and a
    view per (camera, eye), camera-major. `raw` is the JSON as read;
    `render` and `dataset` are the sections render and generate add."""

    scene: str
    eyes: List[EyeLabel]
    views: List[View]
    raw: Dict[str, Any] = field(repr=False)

    @property
    def cameras(self) -> List[Dict[str, Any]]:
        """The cameras as the labels record them: intrinsics, distortion, poses."""
        return self.raw["cameras"]

    @property
    def illuminators(self) -> List[Dict[str, Any]]:
        """The lights as the labels record them."""
        return self.raw["illuminators"]

    @property
    def render(self) -> Optional[Dict[str, Any]]:
        """The render section (files and checks, sensor, glint radiometry), or None."""
        return self.raw.get("render")

    @property
    def dataset(self) -> Optional[Dict[str, Any]]:
        """A generated image's dataset section (index, seed, drawn parameters), or None."""
        return self.raw.get("dataset")

    def view(self, camera: Union[int, str] = 0, eye: int = 0) -> View:
        """The view of `camera` (index or name) on `eye`."""
        for v in self.views:
            if (v.camera == camera or v.camera_name == camera) and v.eye == eye:
                return v
        raise KeyError(f"no view of camera {camera!r} on eye {eye} "
                       f"(views: {[(v.camera_name, v.eye) for v in self.views]})")

    def to_json(self) -> str:
        """The labels as JSON text (raw)."""
        return json.dumps(self.raw, indent=2)


def parse_labels(text: str) -> Labels:
    """Labels from the text of a labels file."""
    raw = json.loads(text)
    return Labels(raw["scene"], [EyeLabel._from(e) for e in raw["eyes"]], [View._from(v) for v in raw["views"]], raw)


def load_labels(file: Union[str, os.PathLike]) -> Labels:
    """A labels file written by `purkinje truth`, `render` or `generate`."""
    with open(file, encoding="utf-8") as f:
        return parse_labels(f.read())
