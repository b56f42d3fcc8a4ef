"""A missing layer of edits.gpkg is added without touching the others (issue 18 §1)."""

from __future__ import annotations

import fiona
import pytest
from shapely.geometry import Point

from photodem.algorithms.errors import InputError
from photodem.algorithms.project.edits import (
    EDIT_LAYERS,
    add_edit_layers,
    add_features,
    create_edits,
    missing_edit_layers,
    read_layer,
)


def test_missing_layer_added_others_kept(tmp_path):
    full = create_edits(tmp_path / "full.gpkg", "EPSG:25832")
    add_features(full, "start_points", [(Point(1, 2), {"height": 7.5})])
    part = tmp_path / "edits.gpkg"
    for name in EDIT_LAYERS:
        if name == "breaklines":
            continue
        with fiona.open(str(full), layer=name) as src, \
                fiona.open(str(part), "w", layer=name, **src.meta) as dst:
            dst.writerecords(src)
    assert missing_edit_layers(part) == ["breaklines"]
    assert add_edit_layers(part, "EPSG:25832", ["breaklines", "start_points"]) == ["breaklines"]
    assert missing_edit_layers(part) == []
    assert [p["height"] for _g, p in read_layer(part, "start_points")] == [7.5]
    with fiona.open(str(part), layer="breaklines") as src:
        assert src.schema["geometry"] == "3D LineString" and len(src) == 0
    with pytest.raises(InputError):
        add_edit_layers(part, "EPSG:25832", ["nonsense"])
