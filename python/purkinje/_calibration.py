"""The calibration study (docs/calibration.md) as a function returning data."""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import _purkinje
from ._purkinje import Scene


@dataclass(frozen=True)
class GazePanel:
    """One head position's gaze: the screen targets (n, 2) in mm from the
    screen's top-left corner, and per method its estimates (n, 2), masked
    where it gave none."""

    title: str
    targets_mm: np.ndarray
    estimates_mm: Dict[str, np.ma.MaskedArray]


@dataclass(frozen=True)
class CalibrationStudy:
    """What `purkinje calibrate` writes, as data: `runs` as calibration.json
    holds them (per method, the calibration's results, then per head
    position the test frames' errors; each result with its unit in
    `units`), `text` as calibration.txt, `frames_csv` a row per test frame
    (frames.csv; `frames()` reads it with pandas) and the gaze map's panels."""

    runs: List[Dict[str, Any]]
    text: str
    frames_csv: str
    panels: List[GazePanel]

    def frames(self):
        """frames_csv as a pandas DataFrame."""
        import pandas

        return pandas.read_csv(io.StringIO(self.frames_csv), float_precision="round_trip")


METHODS = ("model-based", "polynomial")


def _panel(title: str, targets: list, estimates: list) -> GazePanel:
    by_method = {}
    for method, points in zip(METHODS, estimates):
        data = np.array([p if p is not None else (0.0, 0.0) for p in points], dtype=float).reshape(-1, 2)
        mask = np.array([[p is None] * 2 for p in points], dtype=bool).reshape(-1, 2)
        by_method[method] = np.ma.MaskedArray(data, mask=mask)
    return GazePanel(title, np.array(targets, dtype=float).reshape(-1, 2), by_method)


def calibrate(scene: Scene, *, grid: int = 8, calibration_grid: int = 3,
              head_moves: Sequence[Sequence[float]] = (), tracker_cornea: Optional[Tuple[float, float]] = None,
              fit_radius: bool = False, fit_pupil_depth: bool = False, glint_noise_px: Optional[float] = None,
              pupil_noise_px: Optional[float] = None, noise_frames: int = 64, seed: int = 1,
              tracker_rig: Optional[Scene] = None,
              progress: Optional[Callable[[int, int], None]] = None) -> CalibrationStudy:
    """The calibration study on a rig with a screen, two or more lights and
    one eye, as `purkinje calibrate` runs it (the same options, by their
    long names: head_moves are (x, y, z) mm moves of the eye, tracker_cornea
    the tracker's (R, Q)). `tracker_rig` is the rig as the tracker believes
    it (its camera, lights, screen and eye; e.g. an LED where it is not):
    the frames come from `scene`, the estimates from what the tracker
    believes, the errors from the truth. `progress(done, total)` is called after each
    rendered frame; the GIL is released meanwhile. Raises ValueError for a
    rig it cannot calibrate or a setting out of range."""
    runs_json, text, frames_csv, panels = _purkinje._calibrate(
        scene, grid, calibration_grid, [tuple(m) for m in head_moves],
        tuple(tracker_cornea) if tracker_cornea is not None else None, fit_radius, fit_pupil_depth, glint_noise_px,
        pupil_noise_px, noise_frames, seed, tracker_rig, progress)
    return CalibrationStudy(json.loads(runs_json)["runs"], text, frames_csv, [_panel(*p) for p in panels])
