"""Labelled data sets and trackers over image files: what `purkinje
generate`, `merge` and `track` do, as functions returning data."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Callable, Dict, Optional, Sequence, Tuple, Union

from ._purkinje import Scene
from ._trackers import Detections, Score, _detections

PathLike = Union[str, os.PathLike]


def _with_paths(outcome: Dict[str, object]) -> Dict[str, object]:
    """An outcome's table and manifest as pathlib.Path."""
    return {k: Path(v) if k in ("table", "manifest") else v for k, v in outcome.items()}


def generate(spec: PathLike, output_dir: PathLike, *, count: Optional[int] = None, shard: Tuple[int, int] = (0, 1),
             resume: bool = False, threads: int = 0,
             progress: Optional[Callable[[int, int], None]] = None) -> Dict[str, object]:
    """Renders the labelled set a dataset spec describes into `output_dir`,
    as `purkinje generate` does (docs/datasets.md): each image's files all
    or nothing, then table.csv and manifest.json. `count` overrides the
    spec's (trials: the set's first images, byte for byte); `shard` (i, n)
    renders images i, i + n, ...; `resume` keeps the complete images a
    killed run left; `progress(done, total)` is called after each image.
    Returns the images rendered and resumed, and the table and manifest
    written. The GIL is released while rendering."""
    from . import _files

    index, shards = shard
    return _with_paths(_files.generate(os.fspath(spec), os.fspath(output_dir), count, index, shards, resume, threads,
                                       progress))


def merge(directory: PathLike) -> Dict[str, object]:
    """Joins a set's shard tables and manifests into table.csv and
    manifest.json, as `purkinje merge` does."""
    from . import _files

    return _with_paths(_files.merge(os.fspath(directory)))


def track_set(inputs: Union[PathLike, Sequence[PathLike]], scene: Optional[Scene] = None, *,
              match_radius_px: float = 5.0, min_pupil_overlap: float = 0.5) -> Tuple[Score, Dict[str, Detections]]:
    """purkinje's tracker over labelled images (labels files, images beside
    their labels, or folders), scored against their labels, as `purkinje
    track` does; `scene` is the tracker's rig (its --scene). Returns the
    score and the detections by image name."""
    from . import _files

    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    table, csv, summary, detections = _files.track_set([os.fspath(i) for i in inputs], scene,
                                                       scene.name if scene is not None else "",
                                                       match_radius_px, min_pupil_overlap)
    return Score(json.loads(summary), table, csv), {name: _detections(d) for name, d in detections.items()}
