"""The compare study (docs/compare.md): a rig as it is (the world) against a
version a tracker assumes, as data, images and files."""

from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

from . import _purkinje
from ._purkinje import RenderResult, Scene


@dataclass(frozen=True)
class CompareStudy:
    """What `purkinje compare` writes, as data. `displacements` and `gaze`
    are pandas DataFrames (displacements.csv, gaze.csv; gaze None when the
    study did not calibrate, and `calibration_skipped` says why), `summary`
    the summary's runs as summary.json holds them and `text` as
    summary.txt; `world` and `assumed` the two renders (None without
    images). `write(folder)` writes the command's files and figures."""

    displacements: Any
    gaze: Any
    summary: List[Dict[str, Any]]
    text: str
    calibration_skipped: str
    world: Optional[RenderResult]
    assumed: Optional[RenderResult]
    _run: Any

    def write(self, folder: Union[str, "os.PathLike[str]"], *, figures: bool = True) -> List[Path]:
        """The files `purkinje compare` writes into `folder` (created if
        missing), all or nothing, and with `figures` its figures and
        index.md (matplotlib). Returns the files written. Raises OutputError
        when they cannot be written."""
        from . import _files

        folder = Path(folder)
        _files.write_compare(self._run, os.fspath(folder))
        written = [folder / name for name in ("summary.txt", "summary.json", "summary.csv", "displacements.csv")]
        if self.gaze is not None:
            written.append(folder / "gaze.csv")
        if self.world is not None:
            written += [folder / f"{v}.{e}" for v in ("world", "assumed") for e in ("png", "exr", "json")]
        if figures:
            from .figures import compare_figures

            written += compare_figures(folder)
        return written


def _table(text: str):
    import pandas

    return pandas.read_csv(io.StringIO(text), float_precision="round_trip")


def _model(model: Optional[Union[str, "os.PathLike[str]"]]) -> Optional[str]:
    return None if model is None else os.fspath(model)


def compare(world: Scene, assumed: Optional[Scene] = None, *, world_eye: Optional[str] = None,
            assumed_eye: Optional[str] = None, assumed_cornea: Optional[Tuple[float, float]] = None,
            grid: int = 9, cap_deg: float = 15.0, camera: int = 0, gaze_grid: int = 9, calibration_grid: int = 3,
            head_moves: Optional[Sequence[Sequence[float]]] = None, glint_noise_px: Optional[float] = None,
            pupil_noise_px: Optional[float] = None, calibrate: bool = True, images: bool = True, samples: int = 1,
            seed: int = 0, progress: Optional[Callable[[int, int], None]] = None) -> CompareStudy:
    """The compare study, as `purkinje compare` runs it (the same options by
    their long names): `assumed` (default: `world`) is the rig as the
    tracker assumes it; `world_eye` and `assumed_eye` replace an eye's
    anatomy with a preset's (`eye_model_presets()`) or an eye-model file's
    (a path); `assumed_cornea` (R, Q) makes the assumed eye's cornea one
    refracting surface with the keratometric index. `head_moves` default
    to a twelfth of the eye's distance sideways and a sixth away.
    `progress(done, total)` is called after each calibration frame and
    render; the GIL is released meanwhile. Raises ValueError for versions
    that cannot be compared or settings out of range."""
    run, displacements, gaze, summary, text, skipped, world_image, assumed_image = _purkinje._compare(
        world, assumed if assumed is not None else world, _model(world_eye), _model(assumed_eye),
        tuple(assumed_cornea) if assumed_cornea is not None else None, grid, cap_deg, camera, gaze_grid,
        calibration_grid, [tuple(m) for m in head_moves] if head_moves is not None else None, glint_noise_px,
        pupil_noise_px, calibrate, images, samples, seed, progress)
    return CompareStudy(_table(displacements), _table(gaze) if gaze is not None else None,
                        json.loads(summary)["runs"], text, skipped, world_image, assumed_image, run)


@dataclass(frozen=True)
class Sweep:
    """What `purkinje compare --sweep` writes, as data: `table` a pandas
    DataFrame with a row per value, subject and quantity (sweep.csv:
    value, subject, quantity, mean, rms, max, unit), `about` the parameter,
    its unit and meaning, the values and the noise floor (sweep.json).
    `write(folder)` writes the command's files and figure."""

    table: Any
    about: Dict[str, Any]
    _run: Any

    def write(self, folder: Union[str, "os.PathLike[str]"], *, figures: bool = True) -> List[Path]:
        """sweep.csv and sweep.json into `folder` (created if missing), and
        with `figures` sweep.png, figures.json and index.md. Returns the
        files written; raises OutputError when they cannot be written."""
        from . import _files

        folder = Path(folder)
        _files.write_sweep(self._run, os.fspath(folder))
        written = [folder / "sweep.csv", folder / "sweep.json"]
        if figures:
            from .figures import sweep_figures

            written += sweep_figures(folder)
        return written


def sweep_parameters() -> List[Tuple[str, str, str]]:
    """The parameters `sweep` can change: (name, unit, meaning) each."""
    return [tuple(p) for p in _purkinje._sweep_parameters()]


def sweep(world: Scene, parameter: str, start: float, stop: float, steps: int = 11, *, noise_frames: int = 16,
          seed: int = 1, grid: int = 9, cap_deg: float = 15.0, camera: int = 0, gaze_grid: int = 9,
          calibration_grid: int = 3, head_moves: Optional[Sequence[Sequence[float]]] = None,
          glint_noise_px: Optional[float] = None, pupil_noise_px: Optional[float] = None, calibrate: bool = True,
          progress: Optional[Callable[[int, int], None]] = None) -> Sweep:
    """`purkinje compare --sweep PARAMETER=START:STOP:STEPS` on `world`: for
    each value the study (no images) on the world against the world with
    that parameter (`sweep_parameters()`), and the noise floor measured on
    `noise_frames` renders. Raises ValueError for an unknown parameter, a
    value the eye cannot have, or settings out of range."""
    run, table, about = _purkinje._sweep(
        world, parameter, start, stop, steps, noise_frames, seed, grid, cap_deg, camera, gaze_grid,
        calibration_grid, [tuple(m) for m in head_moves] if head_moves is not None else None, glint_noise_px,
        pupil_noise_px, calibrate, progress)
    return Sweep(_table(table), json.loads(about), run)


def displacement_field(world: Scene, assumed: Scene, *, grid: int = 9, cap_deg: float = 15.0, camera: int = 0,
                       pupil_border_points: int = 36):
    """Where each feature lands in `camera`'s image when the world's eye and
    the assumed version's eye fixate the same targets (grid x grid over the
    world's screen, or gaze turns within cap_deg of the eye's own visual
    axis without a screen), as a pandas DataFrame: a row per target and
    feature (each light's glint, the pupil's centre seen through the
    cornea, its ellipse) with both statuses and pixels, du_px, dv_px,
    displacement_px, and the ellipses' semi-axes; NaN where a value does
    not exist. Identical versions give exactly zero. Raises ValueError for
    versions that cannot be compared (other than one eye each, different
    cameras or lights)."""
    import pandas

    text = _purkinje._displacement_csv(world, assumed, grid, cap_deg, camera, pupil_border_points)
    return pandas.read_csv(io.StringIO(text), float_precision="round_trip")
