"""What a parameter's kind means: the predicates the faces switch on, and list splitting."""

from __future__ import annotations

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing.spec import (
    INPUT_PATH_KINDS,
    OUTPUT_KINDS,
    PARAMETER_KINDS,
    Output,
    Parameter,
    split_list,
)


def make(kind: str) -> Parameter:
    return Parameter("p", kind, "P", options=("a", "b") if kind == "enum" else ())


def test_every_kind_has_exactly_one_value_type() -> None:
    for kind in PARAMETER_KINDS:
        p = make(kind)
        types = [p.is_path, p.is_numeric, p.is_choice, p.is_bool, p.is_text,
                 kind == "extent"]
        assert sum(types) == 1, kind
        assert p.is_path == (kind in INPUT_PATH_KINDS or kind in OUTPUT_KINDS
                             or kind == "multiple_rasters")
        assert p.is_output == (kind in OUTPUT_KINDS)
        assert p.is_input_path == (kind in INPUT_PATH_KINDS)


def test_predicates_of_single_kinds() -> None:
    assert make("project").is_project and make("project").is_folder
    assert make("output_folder").is_folder and not make("output_raster").is_folder
    assert make("multiple_rasters").is_list and not make("raster").is_list
    assert make("integer").is_integer and make("integer").is_numeric
    assert not make("number").is_integer
    assert make("model").is_item_name and make("image").is_item_name
    assert not make("string").is_item_name and make("crs").is_text
    assert Output("o", "raster", "O").is_path and not Output("o", "json", "O").is_path


def test_paths_of_a_value() -> None:
    assert make("raster").paths("a.tif") == ["a.tif"]
    assert make("multiple_rasters").paths(["a.tif", "b.tif"]) == ["a.tif", "b.tif"]
    assert make("raster").paths(None) == []


def test_list_splitting_is_one_rule() -> None:
    assert split_list(" a.tif, ,b.tif ") == ["a.tif", "b.tif"]
    assert split_list(["a.tif,b.tif", "c.tif"]) == ["a.tif", "b.tif", "c.tif"]
    assert make("multiple_rasters").convert("a.tif, b.tif") == ["a.tif", "b.tif"]


def test_numbers_are_converted_and_checked() -> None:
    p = Parameter("n", "integer", "N", minimum=0, maximum=3)
    assert p.convert("2") == 2 and isinstance(p.convert(2.0), int)
    for bad in ("2.5", "4", "inf"):
        with pytest.raises(InputError):
            p.convert(bad)
    assert Parameter("x", "number", "X").convert("2.5") == 2.5
