"""OPK CSV dialects: orthority's space-separated, quoted files (a hand-written fixture in that
dialect and, where orthority is installed, orthority's own reading of it), comma, semicolon and
tab files, headers in any case, and an error that names the header found."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.project.importers import (
    detect_exterior_format,
    read_opk_csv,
    sniff_csv_dialect,
)

FIXTURE = Path(__file__).parent / "data" / "orthority_xyz_opk.csv"
CAMERA = "dji fc6310r 5472 3648 brown 0.6666"
EXPECTED = {  # name: (x, y, z, omega, phi, kappa) as written in the fixture
    "DJI_0101": (350012.5, 6250030.25, 412.6, -3.224, -30.04, 87.5),
    "DJI_0102": (350040.75, 6250031.5, 413.1, 29.5, 1.25, -92.0),
    "DJI_0103": (350068.0, 6250029.0, 412.9, 0.5, -0.75, 178.25),
}


def check_block(block) -> None:
    assert [i.name for i in block.images] == list(EXPECTED)
    for img in block.images:
        x, y, z, *opk = EXPECTED[img.name]
        np.testing.assert_allclose(img.eo.position, (x, y, z), atol=1e-9)
        np.testing.assert_allclose(img.eo.opk("degrees"), opk, atol=1e-9)


def test_orthority_dialect_fixture() -> None:
    assert sniff_csv_dialect(FIXTURE.read_text().splitlines()) == (" ", "'")
    assert detect_exterior_format(FIXTURE) == "csv"
    block = read_opk_csv(FIXTURE, angle_unit="degrees", crs="EPSG:32735")
    check_block(block)
    assert {i.camera for i in block.images} == {CAMERA}  # quoted, with spaces
    assert block.images[0].source_name == "DJI_0101.JPG"


def test_fixture_as_orthority_reads_it() -> None:
    param_io = pytest.importorskip("orthority.param_io",
                                   reason="orthority is not installed (make .venv-bench)")
    theirs = param_io.CsvReader(FIXTURE, crs="EPSG:32735").read_ext_param()
    ours = read_opk_csv(FIXTURE, angle_unit="degrees", crs="EPSG:32735")
    assert len(theirs) == len(ours.images) == 3
    for img in ours.images:
        ext = theirs[img.source_name] if img.source_name in theirs else theirs[img.name]
        assert ext["camera"] == img.camera
        np.testing.assert_allclose(img.eo.position, ext["xyz"], atol=1e-9)
        np.testing.assert_allclose(img.eo.opk("radians"), ext["opk"], atol=1e-12)


@pytest.mark.parametrize("sep, quote", [(",", ""), (";", '"'), ("\t", ""), ("  ", '"'),
                                        (",", "'")])
def test_delimiters_quotes_and_header_case(tmp_path: Path, sep: str, quote: str) -> None:
    head = ["FileName", "X", "Y", "Z", "Omega", "PHI", "kappa", "Camera"]
    lines = [sep.join(f"{quote}{h}{quote}" for h in head)]
    for name, values in EXPECTED.items():
        cells = [f"{quote}{name}.tif{quote}", *(repr(v) for v in values), f"{quote}cam{quote}"]
        lines.append(sep.join(cells))
    path = tmp_path / "ext.csv"
    path.write_text("\n".join(lines) + "\n")
    block = read_opk_csv(path, angle_unit="degrees", crs="EPSG:32735")
    check_block(block)
    assert {i.camera for i in block.images} == {"cam"}


def test_orthority_older_names(tmp_path: Path) -> None:
    text = FIXTURE.read_text().replace("'x' 'y' 'z'", "'easting' 'northing' 'altitude'")
    (tmp_path / "old.csv").write_text(text)
    check_block(read_opk_csv(tmp_path / "old.csv", angle_unit="degrees", crs="EPSG:32735"))


def test_missing_columns_name_the_header_found(tmp_path: Path) -> None:
    path = tmp_path / "ext.csv"
    path.write_text("'filename' 'lat' 'lon' 'alt' 'omega' 'phi' 'kappa'\n'a' 1 2 3 0 0 0\n")
    with pytest.raises(InputError) as info:
        read_opk_csv(path, angle_unit="degrees", crs="EPSG:32735")
    text = str(info.value)
    assert "lacks x, y, z" in text and "it has 'filename', 'lat', 'lon', 'alt'" in text
