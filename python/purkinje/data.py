"""Generated data sets in pandas (docs/datasets.md).

    import purkinje.data
    table = purkinje.data.load_table("out/remote_set")
    table[table.pupil_radius_mm > 3][["image", "pupil_center_u_px"]]
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Union

import pandas

from ._labels import Labels, load_labels

PathLike = Union[str, os.PathLike]


def load_table(directory: PathLike) -> pandas.DataFrame:
    """A set's table.csv (one row per image and camera: the drawn values,
    the files with their sizes and CRC-32, glints, the pupil, eye points
    and axes) as a DataFrame, every number exactly as written. An empty cell is NaN (a value that does not
    exist for its status, or an unsharded set's shard columns). Raises
    FileNotFoundError naming the folder when it holds no table (a sharded
    set before `purkinje merge`: then its shard tables are named)."""
    folder = Path(directory)
    table = folder / "table.csv"
    if not table.is_file():
        shards = sorted(p.name for p in folder.glob("table.shard-*.csv"))
        hint = f" (shard tables: {', '.join(shards)}; join them with purkinje.merge or `purkinje merge`)" if shards else ""
        raise FileNotFoundError(f"{folder}: no table.csv{hint}")
    # pandas' default float parser may be an ulp off; the table's numbers
    # are written to read back exactly.
    return pandas.read_csv(table, float_precision="round_trip")


def load_manifest(directory: PathLike) -> dict:
    """A set's manifest.json: counts, bytes, the spec's and table's SHA-1, version."""
    with open(Path(directory) / "manifest.json", encoding="utf-8") as f:
        return json.load(f)


def image_labels(directory: PathLike, row: "pandas.Series") -> Labels:
    """The labels of one table row's image."""
    return load_labels(Path(directory) / row["labels"])
