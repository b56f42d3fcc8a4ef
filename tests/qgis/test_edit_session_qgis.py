"""Tier B: edits.gpkg saved by the standalone tool's edit session opens in real QGIS 3.22 with
the same features (fids, Z, attributes), also while QGIS holds the file open (issue 21)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Tuple

import pytest

pytestmark = pytest.mark.qgis

X0, Y0 = 402300.0, 5674700.0


def _session(root: Path) -> Any:
    from shapely.geometry import LineString, Point, Polygon

    from photodem.algorithms.project.edits import create_edits
    from photodem.plugin.widgets.edit_session import EditSession

    create_edits(root / "edits.gpkg", "EPSG:25832")
    s = EditSession(root)
    s.add("start_points", Point(X0, Y0), {"height": 51.25, "note": "seed"})
    s.add("exclusion_areas", Polygon([(X0, Y0), (X0 + 9, Y0), (X0 + 9, Y0 + 7)]),
          {"action": "keep", "note": "lake"})
    s.add("boundaries", Polygon([(X0 - 20, Y0 - 20), (X0 + 20, Y0 - 20), (X0 + 20, Y0 + 20),
                                 (X0 - 20, Y0 + 20)], [[(X0 - 1, Y0 - 1), (X0 + 1, Y0 - 1),
                                                        (X0, Y0 + 1)]]), {"name": "A"})
    s.add("breaklines", LineString([(X0, Y0, 50.125), (X0 + 5, Y0 + 2, 50.5),
                                    (X0 + 9, Y0 + 1, 49.875)]), {"kind": "breakline"})
    s.add("ground_points", Point(X0 + 1, Y0 + 2, 49.75), {"note": "road"})
    s.add("seamlines", LineString([(X0, Y0 - 30), (X0, Y0 + 30)]), {"note": None})
    s.add("check_points", Point(X0 + 3, Y0 + 4, 50.0625), {"id": "CP1"})
    s.remove("exclusion_areas", s.add("exclusion_areas", Polygon([(X0, Y0), (X0 + 1, Y0),
                                                                  (X0, Y0 + 1)]), {}))
    return s


def qgis_features(path: Path, layer: str) -> Tuple[bool, List[Tuple[int, Any, Dict[str, Any]]]]:
    """(valid, [(fid, shapely geometry, attributes)]) of one layer as QGIS reads it."""
    from qgis.core import QgsVectorLayer
    from shapely import wkb

    vl = QgsVectorLayer(f"{path}|layername={layer}", layer, "ogr")
    if not vl.isValid():
        return False, []
    names = [f.name() for f in vl.fields() if f.name() != "fid"]
    out = []
    for f in vl.getFeatures():
        attrs = {n: (None if f[n] is None or str(f[n]) == "NULL" else f[n]) for n in names}
        out.append((f.id(), wkb.loads(bytes(f.geometry().asWkb())), attrs))
    return True, out


def assert_equal_in_qgis(session: Any) -> None:
    for layer in session.layers():
        valid, got = qgis_features(session.path, layer)
        assert valid, layer
        want = session.features(layer)
        assert [f[0] for f in got] == [f[0] for f in want], layer
        for (_, g1, a1), (_, g2, a2) in zip(got, want):
            assert g1.equals_exact(g2, 1e-9) and g1.has_z == g2.has_z, layer
            if g1.has_z:
                assert [c[2] for c in g1.coords] == [c[2] for c in g2.coords]
            assert a1 == a2, layer


def test_saved_file_opens_in_qgis_with_equal_features(qgis_app, tmp_path) -> None:
    from qgis.core import QgsVectorLayer

    s = _session(tmp_path)
    s.save()
    assert_equal_in_qgis(s)
    vl = QgsVectorLayer(f"{s.path}|layername=breaklines", "b", "ogr")
    assert vl.crs().authid() == "EPSG:25832" and vl.wkbType() in (1002, -2147483646)
    assert [f.id() for f in QgsVectorLayer(f"{s.path}|layername=exclusion_areas", "e",
                                           "ogr").getFeatures()] == [1]


def test_qgis_reads_the_file_while_it_is_saved_again(qgis_app, tmp_path) -> None:
    from qgis.core import QgsVectorLayer
    from shapely.geometry import Point

    s = _session(tmp_path)
    s.save()
    held = QgsVectorLayer(f"{s.path}|layername=check_points", "held", "ogr")
    assert held.isValid() and held.featureCount() == 1
    for k in range(5):  # QGIS keeps its layer open across every save
        s.add("check_points", Point(X0 + k, Y0 - 5, 50.0 + k), {"id": f"P{k}"})
        s.save()
        assert held.isValid() and len(list(held.getFeatures())) >= 1
        assert_equal_in_qgis(s)
    held.dataProvider().reloadData()
    assert held.featureCount() == 6


def test_a_file_edited_in_qgis_keeps_the_operators_changes(qgis_app, tmp_path) -> None:
    """QGIS adds a feature with its own edit buffer; the session sees it after loading again
    and writes it back unchanged with its own edit."""
    from qgis.core import QgsFeature, QgsGeometry, QgsPointXY, QgsVectorLayer
    from shapely.geometry import Point

    from photodem.plugin.widgets.edit_session import EditSession

    s = _session(tmp_path)
    s.save()
    vl = QgsVectorLayer(f"{s.path}|layername=start_points", "sp", "ogr")
    vl.startEditing()
    f = QgsFeature(vl.fields())
    f.setGeometry(QgsGeometry.fromPointXY(QgsPointXY(X0 + 7, Y0 + 7)))
    f["height"], f["note"] = 60.5, "qgis"
    assert vl.addFeature(f) and vl.commitChanges()
    again = EditSession(tmp_path)
    assert [a["note"] for _, _, a in again.features("start_points")] == ["seed", "qgis"]
    again.add("start_points", Point(X0 + 8, Y0 + 8), {"height": 61.0, "note": "here"})
    again.save()
    assert_equal_in_qgis(again)
