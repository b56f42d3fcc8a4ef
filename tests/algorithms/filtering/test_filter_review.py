"""Filter review: re-filter an area, compare before/after, patch the DTM only on accept."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
import rasterio
from affine import Affine
from shapely.geometry import box

from photodem.algorithms.errors import InputError
from photodem.algorithms.filtering.review import accept_refilter, refilter_area
from photodem.algorithms.processing import registry

X0, Y0, RES, N = 400000.0, 5600000.0, 0.5, 160
T = Affine(RES, 0, X0, 0, -RES, Y0)


@pytest.fixture(scope="module")
def filtered(tmp_path_factory):
    """A sloped plane with three houses, filtered with the default preset."""
    root = tmp_path_factory.mktemp("review")
    rows, cols = np.mgrid[0:N, 0:N]
    z = 100.0 + 0.02 * cols + 0.01 * rows
    for r, c in ((30, 30), (90, 100), (120, 40)):
        z[r:r + 16, c:c + 20] += 8.0
    with rasterio.open(root / "dsm.tif", "w", driver="GTiff", width=N, height=N, count=1,
                       dtype="float32", crs="EPSG:25832", transform=T, nodata=-9999) as dst:
        dst.write(z.astype(np.float32), 1)
    out = registry.run("filter_lowpass", {"input": str(root / "dsm.tif"),
                                          "output": str(root / "dtm")})
    return root, out


def digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_refilter_writes_nothing_and_compares_inside_the_area(filtered):
    root = filtered[0]
    dtm = root / "dtm" / "dtm.tif"
    before = {p.name: digest(p) for p in (root / "dtm").iterdir() if p.is_file()}
    area = box(X0 + 40, Y0 - 70, X0 + 70, Y0 - 40)  # around the second house
    review = refilter_area(root / "dsm.tif", dtm, area, preset="urban")
    assert {p.name: digest(p) for p in (root / "dtm").iterdir() if p.is_file()} == before
    assert review["inside"].sum() == 60 * 60
    assert review["stats"]["count"] == 60 * 60
    # the house is eliminated before and after; the terrain under it is the plane
    assert 0.05 < review["eliminated"]["before"] < 0.3
    assert review["eliminated"]["after"] == pytest.approx(review["eliminated"]["before"],
                                                          abs=0.05)
    assert abs(review["stats"]["median"]) < 0.05
    with pytest.raises(InputError, match="outside"):
        refilter_area(root / "dsm.tif", dtm, box(X0 - 500, Y0 - 500, X0 - 400, Y0 - 400))


def test_accept_patches_only_the_area(filtered, tmp_path):
    import shutil

    root, _ = filtered
    folder = tmp_path / "dtm"
    shutil.copytree(root / "dtm", folder)
    area = box(X0 + 10, Y0 - 40, X0 + 40, Y0 - 10)
    review = refilter_area(root / "dsm.tif", folder / "dtm.tif", area, preset="flat",
                           overrides={"threshold": 0.3})
    with rasterio.open(folder / "dtm.tif") as src:
        old = src.read(1)
    written = accept_refilter(folder / "dtm.tif", review)
    assert written["mask"] is not None
    with rasterio.open(folder / "dtm.tif") as src:
        new = src.read(1)
    row, col, h, w = review["window"]
    inside = np.zeros(old.shape, bool)
    inside[row:row + h, col:col + w] = review["inside"]
    assert np.array_equal(new[~inside], old[~inside])
    assert np.allclose(new[inside], review["new"][review["inside"]], atol=1e-4)
