"""filter_evaluate: ISPRS Type I/II, total error and kappa against closed forms; DTM checks."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.errors import InputError
from photodem.algorithms.filtering.evaluate import (
    Confusion,
    confusion,
    evaluate,
    read_label_text,
    run_filter_evaluate,
)
from photodem.algorithms.processing import registry
from photodem.algorithms.raster.io import write_raster

CRS = "EPSG:25832"


def shared_data(name: str) -> Path:
    """tests/conftest.py's shared_data (skips when ../shared/data is absent).

    Loaded by path: every conftest module is named "conftest", so the name may point to another.
    """
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "photodem_tests_root_conftest", Path(__file__).resolve().parents[2] / "conftest.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.shared_data(name)


def _table(a: int, b: int, c: int, d: int) -> tuple:
    """(labels, reference) arrays with exactly the given 2 × 2 counts, shuffled."""
    ref = np.repeat([0, 0, 1, 1], [a, b, c, d])
    lab = np.repeat([0, 1, 0, 1], [a, b, c, d])
    order = np.random.default_rng(0).permutation(ref.size)
    return lab[order], ref[order]


def _write_labels(path: Path, labels, xyz=None, sep: str = "\t") -> Path:
    if xyz is None:
        path.write_text("".join(f"{int(v)}\n" for v in labels))
    else:
        path.write_text("".join(f"{x:.2f}{sep}{y:.2f}{sep}{z:.2f}{sep}{int(v)}\n"
                                for (x, y, z), v in zip(xyz, labels)))
    return path


# -- closed forms ---------------------------------------------------------------------------------


def test_confusion_counts_and_measures_closed_form() -> None:
    lab, ref = _table(40, 10, 5, 45)
    conf = confusion(lab, ref)
    assert (conf.a, conf.b, conf.c, conf.d, conf.n) == (40, 10, 5, 45, 100)
    assert conf.type_i == pytest.approx(10 / 50)
    assert conf.type_ii == pytest.approx(5 / 50)
    assert conf.total_error == pytest.approx(15 / 100)
    # p0 = 0.85, pe = (50·45 + 50·55)/100² = 0.5 → κ = 0.35/0.5 = 0.7
    assert conf.kappa == pytest.approx(0.7)
    d = conf.to_dict()
    assert d["type_i_pct"] == pytest.approx(20.0) and d["type_ii_pct"] == pytest.approx(10.0)
    assert d["total_error_pct"] == pytest.approx(15.0) and d["kappa_pct"] == pytest.approx(70.0)
    assert d["reference_ground"] == 50 and d["labelled_ground"] == 45


def test_confusion_unbalanced_kappa_closed_form() -> None:
    a, b, c, d = 700, 30, 120, 150
    conf = confusion(*_table(a, b, c, d))
    n = a + b + c + d
    p0 = (a + d) / n
    pe = ((a + b) * (a + c) + (c + d) * (b + d)) / n**2
    assert conf.kappa == pytest.approx((p0 - pe) / (1 - pe), rel=1e-12)
    assert conf + conf == Confusion(2 * a, 2 * b, 2 * c, 2 * d)


def test_kappa_perfect_inverted_all_ground_and_random() -> None:
    rng = np.random.default_rng(1)
    ref = (rng.random(200_000) < 0.43).astype(np.int8)
    g, o = int((ref == 0).sum()), int((ref == 1).sum())
    perfect = confusion(ref, ref)
    assert perfect.kappa == 1.0 and perfect.total_error == 0.0
    inverted = confusion(1 - ref, ref)
    assert inverted.total_error == 1.0
    assert inverted.kappa == pytest.approx(-2 * g * o / (g * g + o * o), rel=1e-12)
    balanced = np.repeat([0, 1], 500)
    assert confusion(1 - balanced, balanced).kappa == pytest.approx(-1.0)
    ground = confusion(np.zeros_like(ref), ref)  # "everything is ground": p0 = pe
    assert ground.kappa == pytest.approx(0.0, abs=1e-12)
    assert ground.type_i == 0.0 and ground.type_ii == 1.0
    assert ground.total_error == pytest.approx(o / ref.size)
    noise = confusion((rng.random(ref.size) < 0.5).astype(np.int8), ref)  # independent labels
    assert abs(noise.kappa) < 0.01
    assert noise.total_error == pytest.approx(0.5, abs=0.01)


def test_kappa_undefined_when_both_use_one_class() -> None:
    conf = confusion(np.zeros(10, int), np.zeros(10, int))
    assert math.isnan(conf.kappa) and conf.to_dict()["kappa_pct"] is None
    assert math.isnan(conf.type_ii) and conf.to_dict()["type_ii_pct"] is None
    assert confusion([0, 1], [0, 1], valid=[False, False]).to_dict()["total_error_pct"] is None


# -- reading labels -------------------------------------------------------------------------------


def test_read_isprs_style_text_and_columns(tmp_path: Path) -> None:
    xyz = np.array([[10.0, 20.0, 1.0], [11.0, 20.0, 5.0], [12.0, 20.0, 1.2]])
    ls = read_label_text(_write_labels(tmp_path / "s.txt", [0, 1, 0], xyz))
    assert ls.labels.tolist() == [0, 1, 0] and np.allclose(ls.xyz, xyz)
    # comma separated, header naming the label column (not the last), comments, blank lines
    (tmp_path / "h.csv").write_text("# exported\nclass,x,y,z,intensity\n1,0,0,0,9\n\n0,1,1,1,7\n")
    ls = read_label_text(tmp_path / "h.csv")
    assert ls.labels.tolist() == [1, 0] and ls.xyz is None
    assert read_label_text(tmp_path / "h.csv", column=1).labels.tolist() == [1, 0]
    # one label per line (labels.txt)
    ls = read_label_text(_write_labels(tmp_path / "l.txt", [1, 1, 0]))
    assert ls.labels.tolist() == [1, 1, 0] and ls.xyz is None


def test_bad_labels_are_one_line_errors(tmp_path: Path) -> None:
    (tmp_path / "bad.txt").write_text("0\n2\n")
    with pytest.raises(InputError, match=r"label 2 .*0 \(ground\) or 1"):
        read_label_text(tmp_path / "bad.txt")
    with pytest.raises(InputError, match="does not exist"):
        read_label_text(tmp_path / "missing.txt")
    (tmp_path / "short.txt").write_text("1 2 3 0\n1 2\n")
    with pytest.raises(InputError, match="Line 2"):
        read_label_text(tmp_path / "short.txt", column=4)
    lab = _write_labels(tmp_path / "lab.txt", [0, 1])
    ref = _write_labels(tmp_path / "ref.txt", [0, 1, 1])
    with pytest.raises(InputError, match="2 labels but the reference has 3 points"):
        evaluate(lab, ref)


# -- rasters --------------------------------------------------------------------------------------


def test_mask_rasters_same_and_other_grid(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    t = Affine(1.0, 0, 1000.0, 0, -1.0, 2000.0)
    ref = (rng.random((40, 60)) < 0.3).astype(np.uint8)
    lab = ref.copy()
    lab[:10] = 0  # the first 10 rows: every object accepted as ground
    lab[35:, :] = 255  # nodata: not counted
    write_raster(tmp_path / "ref.tif", ref, t, CRS, nodata=255)
    write_raster(tmp_path / "lab.tif", lab, t, CRS, nodata=255)
    res = evaluate(tmp_path / "lab.tif", tmp_path / "ref.tif")
    c = res["classification"]
    expected = confusion(lab[:35], ref[:35])
    assert (c["a"], c["b"], c["c"], c["d"]) == (expected.a, expected.b, expected.c, expected.d)
    assert c["c"] == int(ref[:10].sum()) and c["b"] == 0
    assert res["unlabelled"] == 5 * 60
    # the reference on a 0.5 m grid covering the same area: read on the labels' grid (nearest)
    fine = np.repeat(np.repeat(ref, 2, axis=0), 2, axis=1)
    write_raster(tmp_path / "ref_fine.tif", fine, Affine(0.5, 0, 1000.0, 0, -0.5, 2000.0), CRS,
                 nodata=255)
    res2 = evaluate(tmp_path / "lab.tif", tmp_path / "ref_fine.tif")
    assert res2["classification"] == c
    # a mask raster against ISPRS-style reference points: sampled at the points
    rows, cols = np.mgrid[0:40, 0:60]
    xyz = np.column_stack([1000.5 + cols.ravel(), 1999.5 - rows.ravel(), np.zeros(rows.size)])
    pts = _write_labels(tmp_path / "pts.txt", ref.ravel(), xyz)
    res3 = evaluate(tmp_path / "lab.tif", pts)
    assert res3["classification"] == c and res3["unlabelled"] == 5 * 60
    # a mask with values other than 0/1
    write_raster(tmp_path / "bad.tif", np.full((4, 4), 7, np.uint8), t, CRS, nodata=255)
    with pytest.raises(InputError, match="value 7"):
        evaluate(tmp_path / "bad.tif", tmp_path / "ref.tif")
    with pytest.raises(InputError, match="text file"):
        evaluate(_write_labels(tmp_path / "l.txt", [0]), tmp_path / "ref.tif")


# -- DTM accuracy ---------------------------------------------------------------------------------


def test_dtm_against_reference_and_at_ground_points(tmp_path: Path) -> None:
    t = Affine(1.0, 0, 1000.0, 0, -1.0, 2000.0)
    rows, cols = np.mgrid[0:50, 0:50].astype(np.float32)
    plane = 100.0 + 0.1 * cols - 0.05 * rows
    write_raster(tmp_path / "ref_dtm.tif", plane, t, CRS)
    shift = np.where(cols < 25, 0.1, 0.3).astype(np.float32)  # mean 0.2, std 0.1
    write_raster(tmp_path / "dtm.tif", plane + shift, t, CRS)
    # points on the reference plane (cell centres), two ground, one object 8 m above
    xy = np.array([[1010.5, 1980.5], [1040.5, 1960.5], [1020.5, 1970.5]])
    col, row = xy[:, 0] - 1000.5, 1999.5 - xy[:, 1]
    z = 100.0 + 0.1 * col - 0.05 * row + np.array([0.0, 0.0, 8.0])
    pts = _write_labels(tmp_path / "ref.txt", [0, 0, 1], np.column_stack([xy, z]))
    lab = _write_labels(tmp_path / "lab.txt", [0, 0, 1])
    res = evaluate(lab, pts, dtm=tmp_path / "dtm.tif", reference_dtm=tmp_path / "ref_dtm.tif")
    d = res["dtm"]
    assert d["count"] == 2500
    assert d["mean"] == pytest.approx(0.2, abs=1e-5)
    assert d["rms"] == pytest.approx(math.sqrt((0.01 + 0.09) / 2), abs=1e-5)
    assert d["std"] == pytest.approx(0.1 * math.sqrt(2500 / 2499), abs=1e-5)
    g = res["dtm_at_ground_points"]
    assert g["count"] == 2 and g["outside"] == 0
    assert g["mean"] == pytest.approx(0.2, abs=1e-5) and g["max"] == pytest.approx(0.3, abs=1e-5)
    assert res["classification"]["kappa_pct"] == pytest.approx(100.0)
    with pytest.raises(InputError, match="no DTM"):
        evaluate(lab, pts, reference_dtm=tmp_path / "ref_dtm.tif")
    with pytest.raises(InputError, match="needs a reference DTM"):
        evaluate(lab, lab, dtm=tmp_path / "dtm.tif")


def test_run_writes_report_json_and_csv_atomically(tmp_path: Path) -> None:
    lab = _write_labels(tmp_path / "lab.txt", [0, 1, 1, 0])
    ref = _write_labels(tmp_path / "ref.txt", [0, 1, 0, 0])
    out = run_filter_evaluate(lab, ref, tmp_path / "out")
    assert out["metrics"]["type_i_pct"] == pytest.approx(100 / 3)
    assert out["metrics"]["type_ii_pct"] == 0.0
    report = json.loads(Path(out["report"]).read_text())
    assert report["classification"]["b"] == 1
    header, row = Path(out["csv"]).read_text().splitlines()
    assert header.startswith("labels,reference,n,a,b,c,d,type_i_pct")
    assert row.split(",")[2:7] == ["4", "2", "1", "0", "1"]
    # a failing run leaves nothing behind
    with pytest.raises(InputError):
        run_filter_evaluate(lab, _write_labels(tmp_path / "r3.txt", [0]), tmp_path / "out2")
    assert not (tmp_path / "out2").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_registry_runs_filter_evaluate(tmp_path: Path) -> None:
    lab = _write_labels(tmp_path / "lab.txt", [0, 1])
    ref = _write_labels(tmp_path / "ref.txt", [0, 1])
    res = registry.run("filter_evaluate", {"labels": str(lab), "reference": str(ref),
                                           "output": str(tmp_path / "ev")})
    assert res["metrics"]["kappa_pct"] == 100.0 and res["report"].endswith("report.json")
    assert json.dumps(res)  # JSON-ready


# -- real data ------------------------------------------------------------------------------------


def test_isprs_samp11_trivial_classifiers(tmp_path: Path) -> None:
    samp11 = shared_data("isprs_filtertest") / "samp11.txt"
    ref = read_label_text(samp11)
    assert ref.labels.size == 38010 and ref.xyz is not None
    everything_ground = _write_labels(tmp_path / "ground.txt", np.zeros(ref.labels.size))
    res = evaluate(everything_ground, samp11)["classification"]
    assert (res["reference_ground"], res["reference_objects"]) == (21786, 16224)
    assert res["total_error_pct"] == pytest.approx(100 * 16224 / 38010)  # ≈ 43 % (README)
    assert round(res["total_error_pct"]) == 43
    assert res["type_i_pct"] == 0.0 and res["type_ii_pct"] == 100.0
    assert res["kappa_pct"] == pytest.approx(0.0, abs=1e-9)
    perfect = _write_labels(tmp_path / "perfect.txt", ref.labels)
    assert evaluate(perfect, samp11)["classification"]["kappa_pct"] == pytest.approx(100.0)
