"""Figures of the calibration and compare studies, drawn with matplotlib
from the files the studies write (docs/compare.md says why matplotlib).

`purkinje calibrate` and `purkinje compare` run this module after writing
their data: ``python3 -m purkinje.figures calibration|compare|sweep
FOLDER``. From Python, `calibration_figures(folder)`,
`compare_figures(folder)` and `sweep_figures(folder)` draw the same;
`draw_labels(ax, view)` draws an image's labels over it (the gallery in
docs/rendering.md). Every arrow panel has its own scale, given by a key arrow
in the panel and written, with each panel's colour range, to
``figures.json`` beside the figures, so that a test (or a reader) can
check what a figure shows.
"""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

PathLike = Union[str, "os.PathLike[str]"]

METHODS = ("model-based", "polynomial")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # files only: no display needed
    import matplotlib.pyplot as plt

    return plt


def _read_csv(path: Path):
    import pandas

    return pandas.read_csv(path, float_precision="round_trip")


def nice_length(largest: float) -> float:
    """The largest 1-2-5 step not above `largest` (for a key arrow); 0 for 0."""
    if not largest > 0:
        return 0.0
    decade = 10.0 ** math.floor(math.log10(largest))
    for step in (5, 2, 1):
        if step * decade <= largest:
            return step * decade
    return decade


def _atomically(path: Path, write) -> None:
    """`write(temporary)` then the temporary renamed to `path`: the file is
    whole or absent, and no temporary is left when writing fails."""
    temporary = path.with_name(f".{path.stem}.tmp{path.suffix}")
    try:
        write(temporary)
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()


def _save(fig, path: Path) -> None:
    _atomically(path, lambda t: fig.savefig(t, format=path.suffix.lstrip("."), dpi=100))


def _number(value: float) -> Optional[float]:
    """A finite float, or None (JSON has no NaN)."""
    value = float(value)
    return value if math.isfinite(value) else None


def _grid(x: np.ndarray, y: np.ndarray, values: np.ndarray) -> Tuple[np.ndarray, List[float]]:
    """Values at targets on a regular grid as an image (rows along y), NaN
    where a target has none, and the image's extent (cells centred on the
    targets)."""
    xs, ys = np.unique(x), np.unique(y)
    image = np.full((len(ys), len(xs)), np.nan)
    image[np.searchsorted(ys, y), np.searchsorted(xs, x)] = values
    dx = (xs[-1] - xs[0]) / (len(xs) - 1) if len(xs) > 1 else 1.0
    dy = (ys[-1] - ys[0]) / (len(ys) - 1) if len(ys) > 1 else 1.0
    return image, [xs[0] - dx / 2, xs[-1] + dx / 2, ys[0] - dy / 2, ys[-1] + dy / 2]


def _spacing(x: np.ndarray, y: np.ndarray) -> float:
    steps = [np.diff(np.unique(v)).min() for v in (x, y) if len(np.unique(v)) > 1]
    return float(min(steps)) if steps else 1.0


def _field_panel(plt, fig, ax, title: str, x: np.ndarray, y: np.ndarray, u: np.ndarray, v: np.ndarray,
                 heat: np.ndarray, heat_label: str, arrow_unit: str, y_down: bool,
                 xlabel: str, ylabel: str, diverging: bool = False,
                 no_arrows: str = "no displacement") -> Dict[str, Any]:
    """One panel: `heat` as a colour map over the grid with its own colour
    bar, and arrows (u, v) at the targets with their own scale (the longest
    spans 0.9 of the grid's spacing) and a key arrow. Returns what it drew."""
    finite = np.isfinite(heat)
    largest_heat = float(np.abs(heat[finite]).max()) if finite.any() else 0.0
    image, extent = _grid(x, y, heat)
    if diverging:
        limit = largest_heat if largest_heat > 0 else 1.0
        colour_range = [-limit, limit]
        cmap = "RdBu_r"
    else:
        colour_range = [0.0, largest_heat if largest_heat > 0 else 1.0]
        cmap = "viridis"
    shown = ax.imshow(image, extent=[extent[0], extent[1], extent[3], extent[2]] if y_down else extent,
                      origin="upper" if y_down else "lower", cmap=cmap, vmin=colour_range[0],
                      vmax=colour_range[1], aspect="equal", interpolation="nearest")
    bar = fig.colorbar(shown, ax=ax, shrink=0.85)
    bar.set_label(heat_label)
    lengths = np.hypot(u, v)
    has_arrow = np.isfinite(lengths)
    longest = float(lengths[has_arrow].max()) if has_arrow.any() else 0.0
    spacing = _spacing(x, y)
    # Arrow length in axis units = vector / scale.
    scale = longest / (0.9 * spacing) if longest > 0 else 1.0
    key = nice_length(longest)
    if longest > 0:
        arrows = ax.quiver(x[has_arrow], y[has_arrow], u[has_arrow], v[has_arrow], angles="xy",
                           scale_units="xy", scale=scale, color="white", edgecolor="black", linewidth=0.5,
                           width=0.006)
        ax.quiverkey(arrows, 0.97, 1.05, key, f"{key:g} {arrow_unit}", labelpos="W", coordinates="axes",
                     color="black")
    elif no_arrows:
        ax.text(0.5, 0.5, no_arrows, transform=ax.transAxes, ha="center", va="center",
                bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"})
    ax.plot(x, y, ".", color="black", markersize=2)
    ax.set_title(title, loc="left", fontsize=10)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if y_down and not ax.yaxis_inverted():
        ax.invert_yaxis()
    return {"title": title, "arrow_unit": arrow_unit, "longest_arrow": longest,
            "arrow_scale_per_axis_unit": scale, "key_length": key, "colour_label": heat_label,
            "colour_range": colour_range, "targets": int(len(x)), "targets_with_arrow": int(has_arrow.sum())}


def _panels_figure(plt, rows: int, columns: int):
    fig, axes = plt.subplots(rows, columns, figsize=(6.0 * columns, 4.2 * rows), squeeze=False,
                             constrained_layout=True)
    return fig, axes


def _gaze_figure(plt, panels: Sequence[Tuple[str, str, Any]], path: Path, heat_label: str,
                 suptitle: str, no_arrows: Dict[str, str]) -> List[Dict[str, Any]]:
    """Gaze over the screen: a row per head position, a column per method;
    each panel (position, method, frame with x, y, u, v, heat) its own scales."""
    positions = list(dict.fromkeys(p for p, _, _ in panels))
    fig, axes = _panels_figure(plt, len(positions), len(METHODS))
    drawn = []
    for position, method, data in panels:
        ax = axes[positions.index(position)][METHODS.index(method)]
        drawn.append(_field_panel(plt, fig, ax, f"{method}, {position}", data["x"], data["y"], data["u"],
                                  data["v"], data["heat"], heat_label, "mm", True, "screen x (mm)",
                                  "screen y (mm)", no_arrows=no_arrows[method]))
    fig.suptitle(suptitle)
    _save(fig, path)
    plt.close(fig)
    return drawn


def _write_figures_json(folder: Path, figures: Dict[str, Any]) -> None:
    text = json.dumps(figures, indent=2, allow_nan=False) + "\n"
    _atomically(folder / "figures.json", lambda t: t.write_text(text))


def calibration_figures(folder: PathLike) -> List[Path]:
    """`purkinje calibrate`'s gaze_error.png from its frames.csv: per head
    position and method, the gaze error (deg) as a colour map and an arrow
    from each target to the estimate (mm), each panel with its own scales.
    Returns the files written."""
    folder = Path(folder)
    plt = _pyplot()
    frames = _read_csv(folder / "frames.csv")
    panels = []
    for position in dict.fromkeys(frames["position"]):
        rows = frames[frames["position"] == position]
        for method, prefix in zip(METHODS, ("model", "polynomial")):
            x = rows["target_x_mm"].to_numpy(float)
            y = rows["target_y_mm"].to_numpy(float)
            panels.append((position, method, {
                "x": x, "y": y, "u": rows[f"{prefix}_x_mm"].to_numpy(float) - x,
                "v": rows[f"{prefix}_y_mm"].to_numpy(float) - y,
                "heat": rows[f"{prefix}_error_deg"].to_numpy(float)}))
    drawn = _gaze_figure(plt, panels, folder / "gaze_error.png", "gaze error (deg)",
                         "Gaze error: arrows from each target to the estimate, on the screen\n"
                         "(each panel its own scale and colours)", {m: "no error" for m in METHODS})
    _write_figures_json(folder, {"gaze_error.png": {"panels": drawn}})
    return [folder / "gaze_error.png", folder / "figures.json"]


def _displacement_figure(plt, folder: Path) -> Dict[str, Any]:
    table = _read_csv(folder / "displacements.csv")
    on_screen = "target_x_mm" in table.columns
    xcol, ycol = ("target_x_mm", "target_y_mm") if on_screen else ("gaze_yaw_deg", "gaze_pitch_deg")
    unit = "mm" if on_screen else "deg"
    features = list(dict.fromkeys(table["feature"]))
    titles = []
    for feature in features:
        titles.append((feature, "displacement"))
        if feature == "pupil_ellipse":
            titles.append((feature, "semi-axis"))
    columns = min(3, len(titles))
    rows = (len(titles) + columns - 1) // columns
    fig, axes = _panels_figure(plt, rows, columns)
    drawn = []
    for k, (feature, kind) in enumerate(titles):
        ax = axes[k // columns][k % columns]
        part = table[table["feature"] == feature]
        x = part[xcol].to_numpy(float)
        y = part[ycol].to_numpy(float)
        du = part["du_px"].to_numpy(float)
        dv = part["dv_px"].to_numpy(float)
        xlabel = "screen x (mm)" if on_screen else "gaze yaw (deg)"
        ylabel = "screen y (mm)" if on_screen else "gaze pitch, up (deg)"
        if kind == "displacement":
            # Image v points down: on a pitch-up axis the arrow's y is -dv.
            drawn.append(_field_panel(plt, fig, ax, f"{feature}: assumed - world", x, y, du,
                                      dv if on_screen else -dv, part["displacement_px"].to_numpy(float),
                                      "displacement (px)", "px", on_screen, xlabel, ylabel))
        else:
            change = (part["assumed_semi_axis_1_px"] - part["world_semi_axis_1_px"]).to_numpy(float)
            drawn.append(_field_panel(plt, fig, ax, "pupil ellipse: semi-axis 1 change", x, y,
                                      np.full_like(x, np.nan), np.full_like(x, np.nan), change,
                                      "assumed - world (px)", "px", on_screen, xlabel, ylabel, diverging=True,
                                      no_arrows=""))
    for k in range(len(titles), rows * columns):
        axes[k // columns][k % columns].axis("off")
    fig.suptitle(f"Where each feature moves in the image (assumed - world), over the gaze "
                 f"{'targets' if on_screen else 'cap'} ({unit});\neach panel its own arrow scale and colours")
    _save(fig, folder / "displacements.png")
    plt.close(fig)
    return {"panels": drawn}


def _labels_pupil(labels_file: Path) -> Optional[Tuple[float, float, float]]:
    """The world image's pupil: its centre and larger semi-axis (px), from its labels."""
    labels = json.loads(labels_file.read_text())
    for view in labels.get("views", []):
        ellipse = view.get("pupil", {}).get("ellipse")
        if ellipse:
            return (ellipse["center_u_px"], ellipse["center_v_px"],
                    max(ellipse["semi_axis_1_px"], ellipse["semi_axis_2_px"]))
    return None


def _images_figure(plt, folder: Path) -> Dict[str, Any]:
    from ._render import read_exr

    world = read_exr(folder / "world.exr")["electrons"].astype(np.float64)
    assumed = read_exr(folder / "assumed.exr")["electrons"].astype(np.float64)
    difference = assumed - world
    seen = {name: plt.imread(folder / f"{name}.png") for name in ("world", "assumed")}
    height, width = world.shape
    pupil = _labels_pupil(folder / "world.json")
    if pupil:
        half = max(24, int(round(3 * pupil[2])))
        u0, v0 = int(round(pupil[0])), int(round(pupil[1]))
    else:
        half, u0, v0 = min(width, height) // 4, width // 2, height // 2
    zoom = (max(0, u0 - half), min(width, u0 + half), max(0, v0 - half), min(height, v0 + half))
    limit = float(np.abs(difference).max())
    # Linear within the shot noise of the median pixel: differences smaller
    # than a pixel's noise are drawn faint, larger ones on a log scale, so
    # that a glint's thousands of electrons do not hide the limbus' tens.
    noise = max(1.0, float(np.sqrt(max(np.median(world), 0.0))))
    from matplotlib.colors import SymLogNorm

    norm = SymLogNorm(linthresh=noise, vmin=-(limit or 1), vmax=limit or 1, base=10)
    fig, axes = plt.subplots(2, 3, figsize=(15, 9), constrained_layout=True)
    panels = []
    for row, crop in enumerate((None, zoom)):
        for column, (name, data) in enumerate((("world", seen["world"]), ("assumed", seen["assumed"]),
                                               ("assumed - world", difference))):
            ax = axes[row][column]
            part = data if crop is None else data[crop[2]:crop[3], crop[0]:crop[1]]
            extent = ([-0.5, width - 0.5, height - 0.5, -0.5] if crop is None
                      else [crop[0] - 0.5, crop[1] - 0.5, crop[3] - 0.5, crop[2] - 0.5])
            if column < 2:
                ax.imshow(part, cmap="gray", vmin=0, vmax=1, extent=extent, interpolation="nearest")
                ax.set_title(f"{name}{' (zoom on the eye)' if crop else ''}: sensor image", loc="left",
                             fontsize=10)
            else:
                shown = ax.imshow(part, cmap="RdBu_r", norm=norm, extent=extent, interpolation="nearest")
                bar = fig.colorbar(shown, ax=ax, shrink=0.85)
                bar.set_label(f"assumed - world (electrons, noise-free;\nlinear within +-{noise:.0f}, "
                              "the median pixel's shot noise)")
                ax.set_title(f"{name}{' (zoom)' if crop else ''}: signed difference", loc="left", fontsize=10)
                panels.append({"title": ax.get_title(loc="left"), "colour_label": bar.ax.get_ylabel(),
                               "colour_range": [-(limit or 1), limit or 1]})
            ax.set_xlabel("u (px)")
            ax.set_ylabel("v (px)")
    fig.suptitle("Both versions rendered with the same seed, and their difference")
    _save(fig, folder / "images.png")
    plt.close(fig)
    _flip(folder, seen, zoom)
    return {"panels": panels, "zoom_px": list(zoom), "difference_max_electrons": limit,
            "linear_within_electrons": noise}


def _flip(folder: Path, seen: Dict[str, np.ndarray], zoom: Tuple[int, int, int, int]) -> None:
    """flip.gif: the zoom of both versions alternating, each second."""
    from PIL import Image, ImageDraw

    frames = []
    for name in ("world", "assumed"):
        crop = seen[name][zoom[2]:zoom[3], zoom[0]:zoom[1]]
        grey = np.clip(np.rint(crop * 255), 0, 255).astype(np.uint8)
        if grey.ndim == 3:
            grey = grey[..., 0]
        image = Image.fromarray(grey, mode="L")
        factor = max(1, 360 // max(image.size))
        image = image.resize((image.size[0] * factor, image.size[1] * factor), Image.NEAREST).convert("RGB")
        ImageDraw.Draw(image).text((6, 6), name, fill=(255, 64, 64))
        frames.append(image)
    _atomically(folder / "flip.gif",
                lambda t: frames[0].save(t, format="GIF", save_all=True, append_images=frames[1:], duration=1000,
                                         loop=0))


def _index(folder: Path, figures: Sequence[str]) -> None:
    summary = (folder / "summary.txt").read_text() if (folder / "summary.txt").exists() else ""
    lines = ["# Compare: the world and the assumed version", "",
             "Every number below is in summary.json and summary.csv; the figures' data in",
             "displacements.csv, gaze.csv and figures.json (docs/compare.md).", ""]
    captions = {
        "images.png": "Both versions rendered with the same seed; the signed difference in electrons.",
        "flip.gif": "The eye in both versions, alternating.",
        "displacements.png": "Where each feature moves in the image over the gaze grid.",
        "gaze_change.png": "What the difference moves the tracker's gaze by, per head position and method.",
        "gaze_error.png": "The tracker's gaze error believing the assumed version, per head position and method.",
    }
    for name in figures:
        lines += [f"## {name}", "", captions.get(name, ""), "", f"![{name}]({name})", ""]
    lines += ["## Summary", "", "```", summary.rstrip(), "```", ""]
    _atomically(folder / "index.md", lambda t: t.write_text("\n".join(lines)))


def compare_figures(folder: PathLike) -> List[Path]:
    """`purkinje compare`'s figures from its files: displacements.png (each
    feature's displacement field), gaze_change.png (when it calibrated),
    images.png and flip.gif (when it rendered), figures.json and index.md.
    Returns the files written."""
    folder = Path(folder)
    plt = _pyplot()
    figures: Dict[str, Any] = {"displacements.png": _displacement_figure(plt, folder)}
    if (folder / "gaze.csv").exists():
        gaze = _read_csv(folder / "gaze.csv")
        panels = []
        for position in dict.fromkeys(gaze["position"]):
            for method in METHODS:
                rows = gaze[(gaze["position"] == position) & (gaze["method"] == method)]
                panels.append((position, method, {
                    "x": rows["target_x_mm"].to_numpy(float), "y": rows["target_y_mm"].to_numpy(float),
                    "u": (rows["believing_assumed_x_mm"] - rows["believing_world_x_mm"]).to_numpy(float),
                    "v": (rows["believing_assumed_y_mm"] - rows["believing_world_y_mm"]).to_numpy(float),
                    "heat": rows["change_deg"].to_numpy(float)}))
        errors = []
        for position in dict.fromkeys(gaze["position"]):
            for method in METHODS:
                rows = gaze[(gaze["position"] == position) & (gaze["method"] == method)]
                x = rows["target_x_mm"].to_numpy(float)
                y = rows["target_y_mm"].to_numpy(float)
                errors.append((position, method, {
                    "x": x, "y": y, "u": rows["believing_assumed_x_mm"].to_numpy(float) - x,
                    "v": rows["believing_assumed_y_mm"].to_numpy(float) - y,
                    "heat": rows["error_believing_assumed_deg"].to_numpy(float)}))
        figures["gaze_error.png"] = {"panels": _gaze_figure(
            plt, errors, folder / "gaze_error.png", "gaze error (deg)",
            "Gaze error believing the assumed version: arrows from each target to the estimate, on the screen\n"
            "(each panel its own scale and colours)", {m: "no error" for m in METHODS})}
        figures["gaze_change.png"] = {"panels": _gaze_figure(
            plt, panels, folder / "gaze_change.png", "gaze change (deg)",
            "What believing the assumed version moves gaze by: arrows from the estimate believing the world\n"
            "to the one believing the assumed, on the screen (each panel its own scale and colours)",
            {"model-based": "no change",
             "polynomial": "no change: the polynomial\nbelieves nothing about the rig"})}
    if (folder / "world.exr").exists():
        figures["images.png"] = _images_figure(plt, folder)
        figures["flip.gif"] = {}
    _write_figures_json(folder, figures)
    _index(folder, list(figures))
    return [folder / name for name in figures] + [folder / "figures.json", folder / "index.md"]


def sweep_figures(folder: PathLike) -> List[Path]:
    """`purkinje compare --sweep`'s sweep.png from sweep.csv and sweep.json:
    against the swept parameter, each glint's displacement, the pupil's,
    and the model-based gaze change per head position (mean dashed, largest
    solid), each panel with the noise floor drawn as a grey band from 0 (the
    detectors' measured RMS error per axis; the gaze s.d. the tracker
    reports with that noise). Also figures.json and index.md."""
    folder = Path(folder)
    plt = _pyplot()
    table = _read_csv(folder / "sweep.csv")
    about = json.loads((folder / "sweep.json").read_text())
    floor = about.get("noise_floor", {})
    name = about["parameter"] + (f" ({about['unit']})" if about.get("unit") else "")
    panels_spec = [
        ("glints", "displacement (px)", lambda t: (t["quantity"] == "displacement") & t["subject"].str.startswith("glint."),
         floor.get("glint_px"), "glint detector noise (RMS per axis)"),
        ("pupil", "displacement (px)", lambda t: (t["quantity"] == "displacement") & t["subject"].str.startswith("pupil"),
         floor.get("pupil_px"), "pupil detector noise (RMS per axis)"),
        ("model-based gaze", "gaze change (deg)",
         lambda t: (t["quantity"] == "gaze_change") & t["subject"].str.startswith("model-based"),
         floor.get("gaze_deg"), "reported gaze s.d. at home (median)"),
    ]
    fig, axes = plt.subplots(1, 3, figsize=(18, 5), constrained_layout=True)
    drawn = []
    for ax, (title, ylabel, select, band, band_label) in zip(axes, panels_spec):
        part = table[select(table)]
        curves = []
        for k, (subject, rows) in enumerate(part.groupby("subject", sort=False)):
            colour = f"C{k}"
            ax.plot(rows["value"], rows["max"], "-o", color=colour, markersize=3, label=f"{subject}: largest")
            ax.plot(rows["value"], rows["mean"], "--", color=colour, label=f"{subject}: mean")
            curves.append({"subject": subject, "largest": _number(rows["max"].max())})
        if band is not None:
            ax.axhspan(0, band, color="grey", alpha=0.3, label=f"{band_label}: {band:.3g}")
        ax.set_xlabel(name)
        ax.set_ylabel(ylabel)
        ax.set_title(title, loc="left", fontsize=10)
        ax.set_ylim(bottom=0)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        drawn.append({"title": title, "curves": curves, "noise_band": _number(band) if band is not None else None})
    fig.suptitle(f"Sweep of the assumed version's {about['parameter']}: {about.get('meaning', '')}")
    _save(fig, folder / "sweep.png")
    plt.close(fig)
    _write_figures_json(folder, {"sweep.png": {"panels": drawn}})
    lines = [f"# Sweep: {name}", "", about.get("meaning", ""), "",
             "The numbers are in sweep.csv (a row per value, subject and quantity) and sweep.json.", "",
             "![sweep.png](sweep.png)", ""]
    _atomically(folder / "index.md", lambda t: t.write_text("\n".join(lines)))
    return [folder / "sweep.png", folder / "figures.json", folder / "index.md"]


#: draw_labels' colour and meaning of a feature, by its status ("ok") or
#: what hid it (occluded_by).
LABEL_COLOURS = {
    "ok": ("#33ff33", "seen"),
    "skin": ("#ff9900", "hidden by skin"),
    "lash": ("#ff33ff", "hidden by a lash"),
    "brow": ("#cc66ff", "hidden by a brow"),
    "mesh": ("#3399ff", "hidden by a mesh"),
    "eye": ("#ff3333", "hidden by the eye"),
    "distractor": ("#00ffff", "distractor (no glint)"),  # a seen distractor, not a status
}


def draw_labels(ax, view, origin: Tuple[float, float] = (0.0, 0.0), scale: float = 1.0) -> Dict[str, int]:
    """Draws one view's labels (a `View` of `Labels`) on an axes showing its
    image: each glint as a +, each pupil-border point as a dot, coloured by
    status (seen; hidden by skin, a lash or brow, a mesh or the eye: `occluded_by`),
    the whole pupil's ellipse dashed and its refracted centre as an x, and
    each distractor the camera sees (a wet eye's highlight, a lens's ghost) as a cyan
    square (key "distractor").
    `origin` and `scale` map pixels into the axes' coordinates (a crop's
    corner, a zoom), with pixel centres at integers as the labels have them.
    Returns how many features of each kind it drew (for a caption or a
    test)."""
    from matplotlib.patches import Ellipse as EllipsePatch

    def at(u: float, v: float) -> Tuple[float, float]:
        return (u - origin[0]) * scale, (v - origin[1]) * scale

    drawn: Dict[str, int] = {}

    def mark(feature, **style) -> None:
        key = feature.occluded_by if feature.status == "occluded" else feature.status
        if key not in LABEL_COLOURS or feature.u_px is None:
            return  # no pixel, or one outside the image
        drawn[key] = drawn.get(key, 0) + 1
        ax.plot(*at(feature.u_px, feature.v_px), color=LABEL_COLOURS[key][0], linestyle="none", **style)

    for g in view.glints:
        mark(g, marker="+", markersize=9, mew=1.5)
    for p in view.pupil.border:
        mark(p, marker="o", markersize=2.5)
    for d in view.distractors:
        if d.status == "ok":
            drawn["distractor"] = drawn.get("distractor", 0) + 1
            ax.plot(*at(d.u_px, d.v_px), marker="s", markersize=9, mew=1.2, markerfacecolor="none",
                    color=LABEL_COLOURS["distractor"][0], linestyle="none")
    e = view.pupil.ellipse
    if e is not None:
        ax.add_patch(EllipsePatch(at(e.center_u_px, e.center_v_px), 2 * e.semi_axis_1_px * scale,
                                  2 * e.semi_axis_2_px * scale, angle=e.angle_deg, fill=False,
                                  edgecolor="#ffff00", linestyle="--", linewidth=0.8))
    c = view.pupil.refracted_center
    if c.u_px is not None:
        ax.plot(*at(c.u_px, c.v_px), marker="x", color="#ffff00", markersize=6)
    return drawn


def main(argv: Sequence[str]) -> int:
    draws = {"calibration": calibration_figures, "compare": compare_figures, "sweep": sweep_figures}
    if len(argv) != 2 or argv[0] not in draws:
        print("usage: python3 -m purkinje.figures calibration|compare|sweep FOLDER", file=sys.stderr)
        return 2
    draw = draws[argv[0]]
    try:
        draw(argv[1])
    except (OSError, KeyError, ValueError) as error:
        print(f"purkinje.figures {argv[0]} {argv[1]}: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
