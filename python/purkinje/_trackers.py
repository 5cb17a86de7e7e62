"""Trackers on numpy images, and scoring of any tracker's detections.

purkinje's detectors are strategies a user's tracker stands beside: a
Detections object from any tracker is scored alike (docs/trackers.md).
Pixel centres sit at integer coordinates, (0, 0) the top-left pixel's
centre, as in OpenCV and every purkinje label.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np

from . import _purkinje
from ._labels import Ellipse
from ._purkinje import RenderResult, Scene


@dataclass
class Glint:
    """A glint as a tracker found it: its center, and what the detector
    measured (energy and peak above the background in DN, area, whether
    saturated, the center's standard deviation where estimated; 0 where
    not). `illuminator` is the light that made it, -1 when not told."""

    u_px: float
    v_px: float
    illuminator: int = -1
    energy_dn: float = 0.0
    peak_dn: float = 0.0
    area_px: int = 0
    saturated: bool = False
    center_sd_u_px: float = 0.0
    center_sd_v_px: float = 0.0

    @property
    def center_px(self) -> np.ndarray:
        """(u, v)"""
        return np.array([self.u_px, self.v_px])


@dataclass
class Pupil:
    """A pupil as a tracker reports it: its center, and its outline and
    confidence (0 to 1) when the tracker gives them."""

    u_px: float
    v_px: float
    ellipse: Optional[Ellipse] = None
    confidence: Optional[float] = None

    @property
    def center_px(self) -> np.ndarray:
        """(u, v)"""
        return np.array([self.u_px, self.v_px])


@dataclass
class Detections:
    """What a tracker found in one image."""

    glints: List[Glint] = field(default_factory=list)
    pupils: List[Pupil] = field(default_factory=list)


def _ellipse(t: Optional[tuple]) -> Optional[Ellipse]:
    return None if t is None else Ellipse(*t)


def _detections(t: tuple) -> Detections:
    glints, pupils = t
    return Detections([Glint(*g) for g in glints], [Pupil(u, v, _ellipse(e), c) for u, v, e, c in pupils])


def _image(image: Union[np.ndarray, RenderResult], bits: Optional[int]) -> tuple:
    if isinstance(image, RenderResult):
        return image.image, image.bits if bits is None else bits
    return np.asarray(image), bits


def detect_glints(image: Union[np.ndarray, RenderResult], *, bits: Optional[int] = None, **settings: Any) -> List[Glint]:
    """Glints in a grey image (2D uint8 or uint16; `bits` its significant
    bits, default 8 or 16: give a 12-bit sensor's RenderResult.image
    bits=12, or pass the RenderResult, which gives its own), brightest first.
    `settings` are BlobGlintSettings' (docs/trackers.md), e.g. threshold=0.1."""
    pixels, bits = _image(image, bits)
    return [Glint(*g) for g in _purkinje._detect_glints(pixels, bits, settings)]


def detect_pupil(image: Union[np.ndarray, RenderResult], glints: Sequence[Glint] = (), *,
                 bits: Optional[int] = None, **settings: Any) -> Optional[Pupil]:
    """The dark pupil in a grey image, or None; `glints` found in the same
    image are masked out. `settings` are StarburstPupilSettings'."""
    pixels, bits = _image(image, bits)
    found = _purkinje._detect_pupil(pixels, bits, list(glints), settings)
    if found is None:
        return None
    ellipse, confidence = found
    e = Ellipse(*ellipse)
    return Pupil(e.center_u_px, e.center_v_px, e, confidence)


class Tracker:
    """purkinje's tracker: glints detected and (told the rig) matched to
    their lights, then the pupil with the glints masked. Without a scene,
    the detectors' defaults; with one, tuned to its camera's optics and
    sensor, and told where its lights put glints on its eye."""

    def __init__(self, scene: Optional[Scene] = None, camera: Union[int, str] = 0, eye: int = 0):
        self._bits: Optional[int] = None
        if scene is None:
            self._tracker = _purkinje._Tracker()
        else:
            index = _purkinje._camera_index(scene, camera, "Tracker")
            self._tracker = _purkinje._Tracker(scene, index, eye)  # checks the index's range
            self._bits = scene.cameras[index].sensor.bits

    @property
    def identifies_glints(self) -> bool:
        """Whether glints are told their lights."""
        return self._tracker.identifies_glints

    def track(self, image: Union[np.ndarray, RenderResult], *, bits: Optional[int] = None) -> Detections:
        """The glints, brightest first, and the pupil if found. `bits`
        defaults to the rig camera's sensor's for a uint16 array (as
        RenderResult.image holds it: values 0 to 2^bits - 1)."""
        pixels, bits = _image(image, bits)
        if bits is None and self._bits is not None and np.asarray(pixels).dtype == np.uint16:
            bits = self._bits
        return _detections(self._tracker.track(pixels, bits))


@dataclass(frozen=True)
class Score:
    """A tracker's score (docs/trackers.md, "Scoring"): `summary` as
    `purkinje score` writes score.json, `table` as it prints, `csv` with a
    row per label and detection."""

    summary: Dict[str, Any]
    table: str
    csv: str


class Scorer:
    """Scores detections against labels, image by image: glints and pupils
    paired with labels nearest first within `match_radius_px`."""

    def __init__(self, *, match_radius_px: float = 5.0, min_pupil_overlap: float = 0.5,
                 score_glints: bool = True, score_pupils: bool = True):
        self._scorer = _purkinje._Scorer(match_radius_px, min_pupil_overlap, score_glints, score_pupils)

    def add(self, image: str, labels: Union[RenderResult, str, os.PathLike], detections: Detections) -> None:
        """One image: its name, its labels (a RenderResult, or a labels
        file written by render or generate), and what was found in it."""
        if isinstance(labels, RenderResult):
            self._scorer.add_render(image, labels, detections)
        else:
            self._scorer.add_labels_file(image, os.fspath(labels), detections)

    def score(self) -> Score:
        """The score of the images added so far."""
        table, csv, summary = self._scorer.score()
        return Score(json.loads(summary), table, csv)


def read_detections(file: Union[str, os.PathLike]) -> Dict[str, Detections]:
    """Another tracker's detections file (CSV, docs/trackers.md,
    "Detections files"), by image name, for Scorer.add. Raises
    FileNotFoundError, or ValueError naming the line, column and rule."""
    return {image: _detections(d) for image, d in _purkinje._read_detections(os.fspath(file), None).items()}
