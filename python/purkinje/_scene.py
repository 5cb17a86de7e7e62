"""Scenes and dataset specs from text, dicts or keyword arguments.

Everything goes through the C++ file readers, so a scene built in Python
is checked by the same rules, with the same messages, as a scene file
(docs/scene-format.md); only the source's name differs:

    build_scene: eyes[0].cornea.radius_mm = -7.8: must be > 0
"""

from __future__ import annotations

import json
import math
import os
from typing import Any, Mapping, Optional, Sequence, Tuple, Union

from . import _purkinje
from ._purkinje import DatasetSpec, DatasetSpecError, Scene, SceneError

Json = Union[str, bytes, Mapping[str, Any]]


def _plain(value: Any) -> Any:
    """numpy arrays and scalars as lists and Python numbers, for json."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _key_path(path: str, key: Union[str, int]) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


def _non_finite(value: Any, path: str = "") -> Optional[Tuple[str, float]]:
    """The key path and value of the first NaN or infinity in `value`, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return path, value
    if isinstance(value, Mapping):
        items = value.items()
    elif isinstance(value, (list, tuple)):
        items = enumerate(value)
    else:
        return None
    for key, item in items:
        found = _non_finite(item, _key_path(path, key))
        if found is not None:
            return found
    return None


def _text(source: Json, name: str, error: type) -> Union[str, bytes]:
    if isinstance(source, (str, bytes)):
        return source
    plain = _plain(source)
    found = _non_finite(plain)
    if found is not None:
        # JSON has no NaN: said as the reader says a bad number.
        where, bad = found
        raise error(f"{name}: {where or '(top level)'} = {bad}: must be a finite number")
    return json.dumps(plain)


def parse_scene(source: Json, name: str = "<string>", folder: Union[str, os.PathLike, None] = None) -> Scene:
    """A scene from scene-file text (str or bytes) or from its dict (``Scene.to_dict()``).

    `name` stands for the file in messages; relative mesh files are found
    in `folder` (default: the current one). Raises SceneError (a
    ValueError) naming the key, the value and the rule.
    """
    return _purkinje._parse_scene_text(_text(source, name, SceneError), name, os.fspath(folder or ""))


def parse_dataset_spec(source: Json, name: str = "<string>", folder: Union[str, os.PathLike, None] = None) -> DatasetSpec:
    """A dataset spec (docs/dataset-format.md) from its text or dict; its
    scene file is found relative to `folder`. Raises DatasetSpecError."""
    return _purkinje._parse_dataset_spec_text(_text(source, name, DatasetSpecError), name, os.fspath(folder or ""))


def _entry(**keys: Any) -> dict:
    return {key: _plain(value) for key, value in keys.items() if value is not None}


def camera(
    *,
    resolution_px: Sequence[int],
    position_mm: Sequence[float],
    name: Optional[str] = None,
    focal_length_mm: Optional[float] = None,
    pixel_pitch_mm: Optional[float] = None,
    intrinsics_px: Optional[Mapping[str, float]] = None,
    distortion: Optional[Mapping[str, float]] = None,
    look_at_mm: Optional[Sequence[float]] = None,
    up: Optional[Sequence[float]] = None,
    rotation_vector_deg: Optional[Sequence[float]] = None,
    rotation_matrix: Optional[Sequence[Sequence[float]]] = None,
    sensor: Optional[Mapping[str, Any]] = None,
) -> dict:
    """A camera entry for build_scene: the scene format's keys
    (docs/scene-format.md, "Cameras"); a key left None is left out."""
    return _entry(name=name, resolution_px=resolution_px, focal_length_mm=focal_length_mm,
                  pixel_pitch_mm=pixel_pitch_mm, intrinsics_px=intrinsics_px, distortion=distortion,
                  position_mm=position_mm, look_at_mm=look_at_mm, up=up, rotation_vector_deg=rotation_vector_deg,
                  rotation_matrix=rotation_matrix, sensor=sensor)


def illuminator(
    *,
    position_mm: Sequence[float],
    name: Optional[str] = None,
    radiant_intensity_w_sr: Optional[float] = None,
    wavelength_nm: Optional[float] = None,
    emitter_diameter_mm: Optional[float] = None,
) -> dict:
    """An illuminator (LED) entry for build_scene ("Illuminators")."""
    return _entry(name=name, position_mm=position_mm, radiant_intensity_w_sr=radiant_intensity_w_sr,
                  wavelength_nm=wavelength_nm, emitter_diameter_mm=emitter_diameter_mm)


def eye(
    *,
    position: Mapping[str, Sequence[float]],
    orientation: Optional[Mapping[str, Any]] = None,
    model: Optional[str] = None,
    cornea: Optional[Mapping[str, float]] = None,
    posterior_cornea: Union[Mapping[str, float], str, None] = None,
    aqueous_index: Optional[float] = None,
    iris: Optional[Mapping[str, float]] = None,
    pupil: Optional[Mapping[str, Any]] = None,
    rotation_center_depth_mm: Optional[float] = None,
    sclera_radius_mm: Optional[float] = None,
    kappa_deg: Optional[Mapping[str, float]] = None,
    appearance: Optional[Mapping[str, Any]] = None,
    eyelids: Optional[Mapping[str, float]] = None,
    face: Optional[Mapping[str, Any]] = None,
    head: Optional[Mapping[str, Sequence[float]]] = None,
    motion: Optional[Mapping[str, float]] = None,
) -> dict:
    """An eye entry for build_scene ("Eyes"): a preset (`model`, see
    eye_model_presets()) with overrides, placed by `position`
    ({"cornea_center_mm": p} or {"rotation_center_mm": p}) and turned by
    `orientation` (yaw_deg/pitch_deg, optical_axis or gaze_target_mm;
    default: looking along world -z). `eyelids` and `face` (with eyelids:
    the periocular face in place of the lid sphere and wall) take the
    scene format's keys; `motion` ({"yaw_deg_s": ..., "pitch_deg_s": ...})
    turns the eye during the exposure (a saccade's motion blur)."""
    return _entry(model=model, cornea=cornea, posterior_cornea=posterior_cornea, aqueous_index=aqueous_index,
                  iris=iris, pupil=pupil, rotation_center_depth_mm=rotation_center_depth_mm,
                  sclera_radius_mm=sclera_radius_mm, kappa_deg=kappa_deg, position=position,
                  orientation=orientation if orientation is not None else {}, appearance=appearance,
                  eyelids=eyelids, face=face, head=head, motion=motion)


def mesh(
    *,
    albedo: float,
    name: Optional[str] = None,
    file: Union[str, os.PathLike, None] = None,
    vertices_mm: Optional[Sequence[Sequence[float]]] = None,
    triangles: Optional[Sequence[Sequence[int]]] = None,
    position_mm: Optional[Sequence[float]] = None,
    rotation_vector_deg: Optional[Sequence[float]] = None,
    scale: Optional[float] = None,
) -> dict:
    """A mesh entry for build_scene ("Meshes"): an OBJ `file`, or
    `vertices_mm` (n, 3) and `triangles` (m, 3) given here."""
    return _entry(name=name, file=os.fspath(file) if file is not None else None, vertices_mm=vertices_mm,
                  triangles=triangles, albedo=albedo, position_mm=position_mm,
                  rotation_vector_deg=rotation_vector_deg, scale=scale)


def screen(
    *,
    size_mm: Sequence[float],
    center_mm: Optional[Sequence[float]] = None,
    top_left_mm: Optional[Sequence[float]] = None,
    right: Optional[Sequence[float]] = None,
    down: Optional[Sequence[float]] = None,
) -> dict:
    """A screen entry for build_scene ("Screen")."""
    return _entry(center_mm=center_mm, top_left_mm=top_left_mm, size_mm=size_mm, right=right, down=down)


def build_scene(
    *,
    cameras: Sequence[Mapping[str, Any]],
    eyes: Sequence[Mapping[str, Any]],
    illuminators: Sequence[Mapping[str, Any]] = (),
    meshes: Sequence[Mapping[str, Any]] = (),
    screen: Optional[Mapping[str, Any]] = None,
    name: str = "scene",
    folder: Union[str, os.PathLike, None] = None,
) -> Scene:
    """A scene from entries made by camera(), illuminator(), eye(), mesh()
    and screen() (or dicts of the same keys), checked as a scene file is.
    Raises SceneError naming "build_scene", the key, the value and the rule."""
    scene: dict = {"format": 1, "name": name, "cameras": list(cameras), "illuminators": list(illuminators),
                   "eyes": list(eyes), "meshes": list(meshes)}
    if screen is not None:
        scene["screen"] = screen
    return parse_scene(scene, name="build_scene", folder=folder)
