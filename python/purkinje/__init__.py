"""purkinje: a physically based simulator of eye-tracker cameras.

Scenes (cameras, near-infrared LEDs, eyes) in, exact labels and rendered
camera images out, as numpy arrays, through the same C++ library as the
``purkinje`` command line, with the same checks and messages. The
tutorial is docs/python.md.

    import purkinje
    scene = purkinje.load_scene("assets/scenes/remote.json")
    labels = purkinje.truth(scene)            # glints, pupil, axes
    result = purkinje.render(scene, seed=1)   # result.image: numpy uint8

``purkinje.data`` reads generated data sets with pandas; ``purkinje.torch``
serves them to PyTorch. Neither is imported here (pandas and torch take
long to import).
"""

from ._purkinje import (
    Camera,
    DatasetSpec,
    DatasetSpecError,
    Eye,
    EyeModel,
    Illuminator,
    Mesh,
    OutputError,
    RenderResult,
    Scene,
    SceneError,
    Screen,
    Sensor,
    __version__,
    eye_model,
    eye_model_presets,
    load_dataset_spec,
    load_scene,
)
from ._calibration import CalibrationStudy, GazePanel, calibrate
from ._compare import CompareStudy, Sweep, compare, displacement_field, sweep, sweep_parameters
from ._labels import (
    DistractorLabel,
    Ellipse,
    EyeLabel,
    GlintLabel,
    Labels,
    Projection,
    PupilLabel,
    RefractedPoint,
    View,
    load_labels,
    parse_labels,
)
from ._scene import (
    build_scene,
    camera,
    eye,
    illuminator,
    mesh,
    parse_dataset_spec,
    parse_scene,
    screen,
)
from ._render import read_exr, render, truth, truth_csv
from ._sets import generate, merge, track_set
from ._trackers import Detections, Glint, Pupil, Score, Scorer, Tracker, detect_glints, detect_pupil, read_detections

__all__ = [
    "__version__",
    "build_scene",
    "calibrate",
    "CalibrationStudy",
    "Camera",
    "camera",
    "compare",
    "CompareStudy",
    "DatasetSpec",
    "DatasetSpecError",
    "detect_glints",
    "detect_pupil",
    "Detections",
    "displacement_field",
    "DistractorLabel",
    "Ellipse",
    "Eye",
    "eye",
    "eye_model",
    "eye_model_presets",
    "EyeLabel",
    "EyeModel",
    "GazePanel",
    "generate",
    "Glint",
    "GlintLabel",
    "Illuminator",
    "illuminator",
    "Labels",
    "load_dataset_spec",
    "load_labels",
    "load_scene",
    "merge",
    "Mesh",
    "mesh",
    "OutputError",
    "parse_dataset_spec",
    "parse_labels",
    "parse_scene",
    "Projection",
    "Pupil",
    "PupilLabel",
    "read_detections",
    "read_exr",
    "RefractedPoint",
    "render",
    "RenderResult",
    "Scene",
    "SceneError",
    "Score",
    "Scorer",
    "Screen",
    "screen",
    "Sensor",
    "Sweep",
    "sweep",
    "sweep_parameters",
    "track_set",
    "Tracker",
    "truth",
    "truth_csv",
    "View",
]
