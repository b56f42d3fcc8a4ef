"""The products of a project: what lies under ``<project>/products/`` and what it is.

The faces show a project's products on the map (QGIS: the *Products* group of the workspace),
so they need to know of every file whether it is a DSM, a DTM, an orthophoto, a mosaic (with
its seamline layer) or a difference model, and of which model or image. A product is
recognised by the algorithm that wrote it — the folder's product marker or a GeoTIFF's
product tag (:mod:`..output_policy`) — and the file name that algorithm gives its main output;
files from older runs without a mark are recognised by the default folders of the algorithms
(``products/dsm/<model>/dsm.tif``, ``products/ortho/<image>.tif``,
``products/mosaic/mosaic.tif``…). Side products (``count``, ``sigma``, ``mask``, visibility)
and staged files (hidden names) are not listed.

Pure Python over the file system: no raster is opened.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Tuple, Union

from ..output_policy import file_product, folder_product

PathLike = Union[str, Path]

#: The kinds of product, in the order the faces list them.
PRODUCT_KINDS = ("dsm", "dtm", "difference", "ortho", "mosaic", "seamlines")
#: Kinds that are elevation models (shown as hillshade + colour ramp).
ELEVATION_KINDS = ("dsm", "dtm")

#: (algorithm id, file name) → kind, for algorithms that write a folder of files.
_FOLDER_FILES: Dict[Tuple[str, str], str] = {
    ("match_model", "dsm.tif"): "dsm",
    ("refine_object_space", "dsm.tif"): "dsm",
    ("filter_lowpass", "dtm.tif"): "dtm",
    ("filter_linear_prediction", "dtm.tif"): "dtm",
    ("dem_compare", "difference.tif"): "difference",
}
#: Algorithm id → kind, for algorithms whose main output is one raster file.
_FILE_ALGORITHMS: Dict[str, str] = {
    "dsm_merge": "dsm",
    "interpolate_dem": "dtm",
    "orthorectify": "ortho",
    "mosaic": "mosaic",
}
#: File names of untagged products, by name (any folder below ``products/``).
_NAMES: Dict[str, str] = {"dsm.tif": "dsm", "dtm.tif": "dtm", "difference.tif": "difference"}
#: Untagged single-file products, by the default folder of their algorithm.
_FOLDERS: Dict[str, str] = {"ortho": "ortho", "mosaic": "mosaic"}
#: Stems of side products written beside a main raster (never listed on their own).
_SIDE_SUFFIXES = ("_count", "_sigma", "_visibility", "_balance")
_RASTER_SUFFIXES = (".tif", ".tiff")


@dataclass(frozen=True)
class Product:
    """One product file.

    Attributes
    ----------
    kind : str
        One of :data:`PRODUCT_KINDS`.
    name : str
        The model, image or product name (``0101_0102``, ``0203``, ``mosaic``).
    path : Path
        The file (absolute).
    algorithm : str or None
        The algorithm that wrote it, when the file or folder is marked.
    """

    kind: str
    name: str
    path: Path

    algorithm: Optional[str] = None


def _hidden(path: Path) -> bool:
    return path.name.startswith(".")


def _seamline_product(path: Path) -> Optional[Product]:
    """``<mosaic>_seamlines.gpkg`` beside its mosaic ``<mosaic>.tif``."""
    if path.suffix.lower() != ".gpkg" or not path.stem.endswith("_seamlines"):
        return None
    stem = path.stem[: -len("_seamlines")]
    mosaic = next((m for m in (path.with_name(stem + s) for s in _RASTER_SUFFIXES)
                   if m.is_file()), None)
    if mosaic is None:
        return None
    return Product("seamlines", stem, path.resolve(), "mosaic")


def classify(path: PathLike) -> Optional[Product]:
    """What the file ``path`` is as a product, or ``None`` for anything else.

    Marked files and folders decide first; untagged files are recognised by name and by the
    algorithms' default folders. Works for files anywhere (a run's output outside a project).
    """
    path = Path(path)
    if _hidden(path) or not path.is_file():
        return None
    seam = _seamline_product(path)
    if seam is not None or path.suffix.lower() not in _RASTER_SUFFIXES:
        return seam
    if path.stem.endswith(_SIDE_SUFFIXES):
        return None
    folder_alg = folder_product(path.parent)
    if folder_alg is not None:
        kind = _FOLDER_FILES.get((folder_alg, path.name.lower()))
        return Product(kind, path.parent.name, path.resolve(), folder_alg) if kind else None
    file_alg = file_product(path)
    if file_alg in _FILE_ALGORITHMS:
        return Product(_FILE_ALGORITHMS[file_alg], path.stem, path.resolve(), file_alg)
    if path.name.lower() in _NAMES:
        return Product(_NAMES[path.name.lower()], path.parent.name, path.resolve(), file_alg)
    kind = _FOLDERS.get(path.parent.name.lower())
    return Product(kind, path.stem, path.resolve(), file_alg) if kind else None


def _sort_key(product: Product) -> Tuple[int, float, str]:
    """By kind (:data:`PRODUCT_KINDS` order), newest first, then by name."""
    try:
        mtime = product.path.stat().st_mtime
    except OSError:
        mtime = 0.0
    return PRODUCT_KINDS.index(product.kind), -mtime, product.name


def find_products(root: PathLike) -> List[Product]:
    """Every product below ``<root>/products/``, sorted by kind and newest first.

    Hidden files and folders (staged outputs, markers) are skipped; a missing ``products/``
    folder gives an empty list.
    """
    base = Path(root) / "products"
    if not base.is_dir():
        return []
    found: List[Product] = []
    for path in sorted(base.rglob("*")):
        if any(part.startswith(".") for part in path.relative_to(base).parts):
            continue
        product = classify(path)
        if product is not None:
            found.append(product)
    return sorted(found, key=_sort_key)


def is_inside(path: PathLike, root: PathLike) -> bool:
    """True when ``path`` lies inside the folder ``root`` (both resolved)."""
    try:
        Path(path).resolve().relative_to(Path(root).resolve())
    except ValueError:
        return False
    return True


__all__ = ["ELEVATION_KINDS", "PRODUCT_KINDS", "Product", "classify", "find_products",
           "is_inside"]
