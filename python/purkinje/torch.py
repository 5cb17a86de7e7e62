"""Generated data sets as a PyTorch dataset (Debian's python3-torch).

    from torch.utils.data import DataLoader
    import purkinje.torch
    dataset = purkinje.torch.EyeDataset("out/remote_set")
    for images, targets in DataLoader(dataset, batch_size=32, shuffle=True, num_workers=2):
        ...  # images: (32, 1, H, W) float32; targets["pupil_center_px"]: (32, 2)

Each item is the sensor image and a dict of tensors from the set's table
(docs/datasets.md): where a label does not exist for its status (a glint
off the cornea, a pupil without a fit), its values are 0 and its `_ok`
mask is False, so that a batch holds no NaN.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import torch as _torch
from PIL import Image
from torch.utils.data import Dataset

from .data import load_table

_ELLIPSE = ("u_px", "v_px", "semi_axis_1_px", "semi_axis_2_px", "angle_deg")
_EYE_VECTORS = ("cornea_center", "rotation_center", "pupil_center")


def _columns(table, names: List[str]) -> np.ndarray:
    return table[names].to_numpy(dtype=np.float64)


class EyeDataset(Dataset):
    """A generated set's images (camera `camera`, default every camera's
    rows) with their labels. Items are (image, target): the image a
    float32 tensor (1, H, W), the sensor's digital numbers over its full
    scale (0 to 1; a PNG of more than 8 bits keeps them in its high bits,
    so this holds for every sensor depth), or with as_float=False the
    PNG's own values (uint8, or int32 holding 16-bit words), a quarter of
    the bytes to move between processes; target a dict of tensors:

    - index (int64); parameters (float64, one per drawn parameter, in the
      order of the dataset's `parameters` names; parameter(target, name) picks one)
    - glints_px (lights, 2), glints_ok (lights,): status "ok" (on the
      cornea, in the image, not hidden)
    - pupil_center_px (2,), pupil_ok: the pupil centre seen through the cornea
    - pupil_ellipse (5,) u, v, semi-axes, angle in degrees, and
      pupil_ellipse_ok; visible_ellipse and visible_ellipse_ok: the part
      the camera sees
    - cornea_center_mm, rotation_center_mm, pupil_center_mm (3,) and
      optical_axis, visual_axis (3,): the eye in world coordinates
    - segmentation (H, W) int64 pixel classes, with segmentation=True

    `transform(image)` and `target_transform(target)` are applied last.
    """

    def __init__(self, directory: Union[str, os.PathLike], transform: Optional[Callable] = None,
                 target_transform: Optional[Callable] = None, *, camera: Optional[str] = None,
                 segmentation: bool = False, as_float: bool = True):
        self.directory = Path(directory)
        table = load_table(self.directory)
        if camera is not None:
            cameras = sorted(set(table["camera"]))
            if camera not in cameras:
                raise ValueError(f"{self.directory}: camera {camera!r} is not in the set (cameras: {', '.join(cameras)})")
            table = table[table["camera"] == camera].reset_index(drop=True)
        if "image" not in table.columns:
            raise ValueError(f"{self.directory}: the set has no sensor images (its spec's outputs.image is false)")
        if segmentation and "segmentation" not in table.columns:
            raise ValueError(f"{self.directory}: the set has no segmentation images (outputs.segmentation)")
        self.as_float = as_float
        self.transform = transform
        self.target_transform = target_transform
        # Plain arrays, not the DataFrame: quick to index, cheap to send to workers.
        self._images = list(table["image"])
        self._segmentation = list(table["segmentation"]) if segmentation else None
        self._index = table["index"].to_numpy(dtype=np.int64)
        first_glint = [c for c in table.columns if c.startswith("glint.") and c.endswith(".status")]
        self.lights = [c[len("glint."):-len(".status")] for c in first_glint]
        self._glint_ok = np.stack([table[f"glint.{l}.status"].to_numpy() == "ok" for l in self.lights], axis=1) \
            if self.lights else np.zeros((len(table), 0), dtype=bool)
        self._glints = np.stack([_columns(table, [f"glint.{l}.u_px", f"glint.{l}.v_px"]) for l in self.lights], axis=1) \
            if self.lights else np.zeros((len(table), 0, 2))
        self._pupil_ok = table["pupil.status"].to_numpy() == "ok"
        self._pupil = _columns(table, ["pupil.u_px", "pupil.v_px"])
        self._ellipse = _columns(table, [f"pupil.ellipse.{k}" for k in _ELLIPSE])
        self._visible = _columns(table, [f"pupil.visible_ellipse.{k}" for k in _ELLIPSE])
        self._eye = {f"{name}_mm": _columns(table, [f"eye.{name}_{a}_mm" for a in "xyz"]) for name in _EYE_VECTORS}
        for axis in ("optical_axis", "visual_axis"):
            self._eye[axis] = _columns(table, [f"eye.{axis}_{a}" for a in "xyz"])
        start, end = table.columns.get_loc("seed") + 1, table.columns.get_loc("image")
        self.parameters = list(table.columns[start:end])
        self._parameters = table[self.parameters].astype(np.float64).to_numpy() if self.parameters else None

    def parameter(self, target: Dict[str, Any], name: str) -> Any:
        """One drawn parameter's values from a target (or a batch's targets)."""
        if name not in self.parameters:
            raise KeyError(f"{name!r} is not a drawn parameter of {self.directory} (parameters: {', '.join(self.parameters)})")
        return target["parameters"][..., self.parameters.index(name)]

    def __len__(self) -> int:
        return len(self._images)

    def _read(self, name: str) -> np.ndarray:
        with Image.open(self.directory / name) as image:
            return np.array(image)  # writable, as torch wants its arrays

    def __getitem__(self, i: int) -> Tuple[Any, Dict[str, Any]]:
        if not -len(self) <= i < len(self):
            raise IndexError(f"EyeDataset index {i} out of range ({len(self)} images)")
        pixels = self._read(self._images[i])
        if self.as_float:
            scale = 255.0 if pixels.dtype == np.uint8 else 65535.0
            image = _torch.from_numpy(pixels.astype(np.float32) / np.float32(scale))[None]
        else:
            image = _torch.from_numpy(pixels.astype(np.int32) if pixels.dtype != np.uint8 else pixels)[None]
        # Few keys: a batch's collation costs per key (25 scalar keys took a
        # quarter of the loader's time).
        target: Dict[str, Any] = {"index": _torch.tensor(self._index[i])}
        target["parameters"] = _torch.from_numpy(
            self._parameters[i].copy() if self._parameters is not None else np.zeros(0))
        ok = self._glint_ok[i]
        target["glints_px"] = _torch.from_numpy(np.where(ok[:, None], self._glints[i], 0.0).astype(np.float32))
        target["glints_ok"] = _torch.from_numpy(ok.copy())
        target["pupil_center_px"] = _torch.from_numpy(
            (self._pupil[i] if self._pupil_ok[i] else np.zeros(2)).astype(np.float32))
        target["pupil_ok"] = _torch.tensor(bool(self._pupil_ok[i]))
        for name, values in (("pupil_ellipse", self._ellipse[i]), ("visible_ellipse", self._visible[i])):
            exists = bool(np.isfinite(values).all())
            target[name] = _torch.from_numpy((values if exists else np.zeros(5)).astype(np.float32))
            target[f"{name}_ok"] = _torch.tensor(exists)
        for name, values in self._eye.items():
            target[name] = _torch.from_numpy(values[i].astype(np.float32))
        if self._segmentation is not None:
            target["segmentation"] = _torch.from_numpy(self._read(self._segmentation[i]).astype(np.int64))
        if self.transform is not None:
            image = self.transform(image)
        if self.target_transform is not None:
            target = self.target_transform(target)
        return image, target
