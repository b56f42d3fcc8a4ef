"""Names of class codes: legend tables, QGIS styles beside the raster, bad legends."""

from __future__ import annotations

from pathlib import Path

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.quality.class_legend import (
    class_label,
    class_style_qml,
    code_key,
    read_class_legend,
    write_class_style,
)


def test_table_with_header_semicolons_and_comments(tmp_path: Path) -> None:
    table = tmp_path / "legend.csv"
    table.write_text("Wert;Klasse\n# roads are paved\n1;Wiese\n3.0;Gebäude\n", encoding="utf-8")
    assert read_class_legend(legend=table) == {"1": "Wiese", "3": "Gebäude"}


def test_style_beside_the_raster_is_the_default_legend(tmp_path: Path) -> None:
    raster = tmp_path / "landcover.tif"
    assert read_class_legend(raster) == {}  # no style: the codes stay
    write_class_style(raster, {3: ("building", "#d6604d"), 1: ("open & meadow", "#c7dc8f")})
    assert read_class_legend(raster) == {"1": "open & meadow", "3": "building"}
    # an explicit legend wins over the style
    table = tmp_path / "names.txt"
    table.write_text("3\tHaus\n", encoding="utf-8")
    assert read_class_legend(raster, table) == {"3": "Haus"}
    assert 'type="paletted"' in class_style_qml({1: ("a", "#000000")})


def test_bad_legends_say_what_is_wrong(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist"):
        read_class_legend(legend=tmp_path / "missing.csv")
    bad = tmp_path / "bad.csv"
    bad.write_text("value,name\n1,open\nroad,2\n", encoding="utf-8")
    with pytest.raises(InputError, match="line 3"):
        read_class_legend(legend=bad)
    empty = tmp_path / "empty.csv"
    empty.write_text("\n", encoding="utf-8")
    with pytest.raises(InputError, match="no 'value,name'"):
        read_class_legend(legend=empty)
    broken = tmp_path / "landcover.qml"
    broken.write_text("<qgis><pipe>", encoding="utf-8")
    assert read_class_legend(tmp_path / "landcover.tif") == {}  # a broken style costs names


def test_labels_and_keys() -> None:
    assert code_key(3.0) == "3" and code_key("7") == "7" and code_key(2.5) == "2.5"
    assert class_label("3", {"3": "building"}) == "building (3)"
    assert class_label("9", {"3": "building"}) == "9"
