"""The block layers of a project (issue 18 §1): footprints and stereo-model overlaps in
``.photodem/block.gpkg``, rewritten only when project.toml is newer."""

from __future__ import annotations

import os

import fiona
import pytest
from shapely.geometry import shape

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.project.block_layers import block_path, write_block_layers
from photodem.algorithms.project.model import Project


@pytest.fixture(scope="module")
def project(tmp_path_factory) -> Project:
    root = tmp_path_factory.mktemp("block") / "p"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return Project.load(root)


def test_layers_fields_and_geometry(project):
    path = write_block_layers(project, force=True)
    assert path == project.root / ".photodem" / "block.gpkg"
    assert fiona.listlayers(str(path)) == ["footprints", "stereo_models"]
    with fiona.open(str(path), layer="footprints") as src:
        feet = {f["properties"]["image"]: shape(f["geometry"]) for f in src}
        assert "25832" in src.crs_wkt
    assert set(feet) == {r.name for r in project.images}
    with fiona.open(str(path), layer="stereo_models") as src:
        models = {f["properties"]["name"]: (f["properties"], shape(f["geometry"])) for f in src}
    assert set(models) == {m.name for m in project.models}
    for m in project.models:
        props, geom = models[m.name]
        assert (props["left"], props["right"]) == (m.left, m.right)
        assert props["b_h"] == pytest.approx(m.b_h, abs=1e-4)
        assert props["overlap_pct"] == pytest.approx(100 * m.overlap, abs=0.1)
        overlap = feet[m.left].intersection(feet[m.right])
        assert geom.symmetric_difference(overlap).area < 1e-6 * overlap.area


def test_rewritten_only_when_project_is_newer(project):
    path = write_block_layers(project, force=True)
    toml = project.project_file
    os.utime(toml, (1e9, 1e9))
    os.utime(path, (1.5e9, 1.5e9))
    write_block_layers(project)
    assert path.stat().st_mtime == 1.5e9  # kept: project.toml is older
    os.utime(toml, (2e9, 2e9))
    write_block_layers(project)
    assert path.stat().st_mtime > 1.5e9 + 1  # rewritten
    assert not [p for p in path.parent.iterdir() if p.name.startswith(".block")]  # no staging


def test_no_crs_is_refused(project):
    bare = Project(root=project.root, name="x", crs="", cameras=project.cameras,
                   images=project.images, models=project.models)
    with pytest.raises(InputError, match="CRS"):
        write_block_layers(bare, force=True)
    assert block_path(bare).is_file()  # the earlier file stays
