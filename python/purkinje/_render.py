"""Truth and rendering, with the command line's defaults."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Dict, Optional, Tuple, Union

import numpy as np

from . import _purkinje
from ._labels import Labels, parse_labels
from ._purkinje import RenderResult, Scene


def truth(scene: Scene, pupil_border_points: int = 36) -> Labels:
    """The exact ground truth of `scene` (as `purkinje truth` computes it):
    every camera's view of every eye, without occlusion by lids or meshes.
    The GIL is released while it is computed."""
    return parse_labels(_purkinje._truth_text(scene, pupil_border_points, "json"))


def truth_csv(scene: Scene, pupil_border_points: int = 36) -> str:
    """The same as `purkinje truth -o labels.csv` writes: a row per feature."""
    return _purkinje._truth_text(scene, pupil_border_points, "csv")


def render(
    scene: Scene,
    camera: Union[int, str] = 0,
    *,
    mode: str = "fast",
    samples_per_pixel: int = 1,
    edge_samples_per_pixel: int = 16,
    pixel_filter: str = "box",
    pixel_filter_width: float = 0.0,
    seed: int = 0,
    noise: bool = True,
    iris_cache_resolution: int = 0,
    reference_photons_per_light: int = 1 << 18,
    per_light_glint_masks: bool = False,
    region: Optional[Tuple[int, int, int, int]] = None,
    threads: int = 0,
) -> RenderResult:
    """Renders one camera (index or name) of `scene` into numpy arrays, as
    `purkinje render` does with the same options (docs/rendering.md): the
    same seed gives the same pixels. `region` (x0, y0, x1, y1) traces only
    those pixels. `pixel_filter` ("box", "gaussian", "blackman-harris") and
    `pixel_filter_width` (px; 0: box 1, the others 3) are --pixel-filter and
    --pixel-filter-width. The GIL is released while rendering."""
    return _purkinje._render(scene, camera, mode, samples_per_pixel, edge_samples_per_pixel, pixel_filter,
                             pixel_filter_width, seed, noise,
                             iris_cache_resolution, reference_photons_per_light, per_light_glint_masks, region,
                             threads)


def _labels(self: RenderResult) -> Labels:
    return parse_labels(self._truth_json())


RenderResult.labels = property(
    _labels, doc="The image's labels (Labels): the truth with lids, skin and meshes hiding what they hide.")


def _write(self: RenderResult, folder: Union[str, os.PathLike], stem: Optional[str] = None) -> Dict[str, Path]:
    from . import _files  # OpenImageIO: loaded when first needed

    return {kind: Path(path) for kind, path in _files.write_render(self, os.fspath(folder), stem).items()}


RenderResult.write = _write
_write.__doc__ = """Writes <stem>.png, .exr and .json into `folder` (created if missing)
as `purkinje render` does, all or nothing; the stem defaults to the
command's, <scene>_<camera>. Returns the paths by kind ("image", "exr",
"labels"). Raises OutputError (an OSError) naming the file."""


def read_exr(file: Union[str, os.PathLike]) -> Dict[str, np.ndarray]:
    """Every plane of an EXR file (`purkinje render`'s: R, electrons, depth,
    N.x, id, glint masks, ...) as float32 arrays (height, width), by name."""
    from . import _files

    return _files.read_exr(os.fspath(file))
