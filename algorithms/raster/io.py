"""Raster and folder outputs that are never left half-written.

Every product is written to a temporary name beside its target and renamed when complete
(:func:`atomic_output`, :func:`staged_folder`), so a failed or cancelled run leaves nothing and an
existing product is replaced only by a complete one. GeoTIFFs are tiled and compressed; final
products are Cloud-Optimised (overviews first, :func:`cog_output`; :func:`write_raster` with
``overviews=True``).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import time
import warnings
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from numpy.typing import NDArray
from rasterio.enums import Resampling
from rasterio.errors import NotGeoreferencedWarning
from rasterio.shutil import copy as gdal_copy

from .. import output_policy
from ..errors import InputError, msg
from ..output_policy import PRODUCT_MARKER as PRODUCT_MARKER  # re-exported
from ..output_policy import PRODUCT_TAG

PathLike = Union[str, Path]

#: Creation options of every GeoTIFF product.
GTIFF_PROFILE: Dict[str, Any] = {
    "driver": "GTiff",
    "tiled": True,
    "blockxsize": 256,
    "blockysize": 256,
    "compress": "deflate",
    "interleave": "pixel",
    "BIGTIFF": "IF_SAFER",
}


def gtiff_profile(width: int, height: int, count: int = 1, dtype: str = "float32",
                  crs: Any = None, **options: Any) -> Dict[str, Any]:
    """The creation profile of a ``height × width`` GeoTIFF of the project.

    :data:`GTIFF_PROFILE` (deflate, 256² tiles) with the size, band count and data type;
    ``crs`` only when one is given (image-space rasters have none; ``None``, ``""`` and an
    empty rasterio CRS count as none); every other profile key
    or creation option (``transform``, ``nodata``, ``predictor`` …) as given. A raster smaller
    than one tile in either direction is written in strips: its tiles would be mostly padding.
    """
    profile = dict(GTIFF_PROFILE)
    profile.update(width=int(width), height=int(height), count=int(count), dtype=dtype,
                   **options)
    if crs:
        profile["crs"] = crs
    if width < GTIFF_PROFILE["blockxsize"] or height < GTIFF_PROFILE["blockysize"]:
        profile.update(tiled=False)
        profile.pop("blockxsize")
        profile.pop("blockysize")
    return profile


def _temp_sibling(path: Path, kind: str = "partial") -> Path:
    """A hidden sibling of ``path`` named after this process (see :mod:`..output_policy`)."""
    return path.with_name(output_policy.staging_name(path.name, kind))


def _product_of_file(path: Path) -> str:
    """The algorithm id to tag ``path`` with: set when it is a main file output of the run."""
    scope = output_policy.current()
    if scope is None or not scope.targets or not scope.is_product_file(path):
        return ""
    return scope.product


#: Staged GeoTIFFs that get the :data:`PRODUCT_TAG` when :func:`open_image` creates them:
#: staging path → algorithm id (set by :func:`atomic_output` and :func:`cog_output`).
_TAG_ON_CREATE: Dict[str, str] = {}


def tag_product(path: PathLike, product: str) -> None:
    """Write the :data:`PRODUCT_TAG` into a finished (not Cloud-Optimised) GeoTIFF.

    Only for a staged GeoTIFF its writer did not create through :func:`open_image` (which
    tags it as it creates it).
    """
    with open_image(path, "r+") as dst:
        dst.update_tags(**{PRODUCT_TAG: product})


@contextlib.contextmanager
def _tagged_on_create(staged: Path, product: str) -> Iterator[None]:
    """Tag ``staged`` with ``product`` when it is created (``""``: no tag), or at the end of
    the block when its writer did not create it through :func:`open_image`."""
    key = os.fspath(staged)
    if product:
        _TAG_ON_CREATE[key] = product
    try:
        yield
        if _TAG_ON_CREATE.pop(key, None):  # written by another writer: tag it now
            tag_product(staged, product)
    finally:
        _TAG_ON_CREATE.pop(key, None)


@contextlib.contextmanager
def atomic_output(path: PathLike, tag: bool = True) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` only on success.

    The suffix is kept (``.tif``) so that drivers recognise the format. On any exception
    (including :class:`~photodem.algorithms.errors.Cancelled`) the temporary file is removed
    and ``path`` stays as it was. The rename is the commit point of the output: SIGINT is held
    back around it, and it is recorded in the run scope (:func:`..output_policy.commit`). A
    GeoTIFF that is a main output of the run gets the product tag as :func:`open_image`
    creates it (``tag=False``: the caller tags it, see :func:`cog_output`).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(output_policy.staging_name(path.stem, suffix=path.suffix))
    product = _product_of_file(path) if tag else ""
    tiff = output_policy.is_tiff(path)
    try:
        with _tagged_on_create(tmp, product if tiff else ""):
            yield tmp
        if product and not tiff:  # other files: a hidden mark beside them
            output_policy.write_marker(output_policy.file_mark(path).parent, product,
                                       time.strftime("%Y-%m-%dT%H:%M:%S"),
                                       output_policy.file_mark(path).name)
        with output_policy.sigint_blocked():
            os.replace(tmp, path)
            output_policy.commit(path)
    finally:
        _remove_with_sidecars(tmp)


def _remove_with_sidecars(path: Path) -> None:
    """Delete a raster file and the sidecars GDAL may have put beside it."""
    for leftover in (path, Path(str(path) + ".aux.xml"), Path(str(path) + ".ovr")):
        if leftover.exists():
            leftover.unlink()


#: Creation options that carry over from a product's profile to its Cloud-Optimised copy.
_COG_OPTIONS = ("tiled", "blockxsize", "blockysize", "compress", "predictor", "zlevel",
                "interleave", "BIGTIFF", "num_threads")


@contextlib.contextmanager
def cog_output(path: PathLike, profile: Dict[str, Any]
               ) -> Iterator[Tuple[Path, Dict[str, Any]]]:
    """Yield a scratch path and the profile to write it with; on success the scratch file
    (with the internal overviews built into it) becomes a Cloud-Optimised GeoTIFF at ``path``,
    atomically like :func:`atomic_output`, with the creation options of ``profile``.

    GDAL can put overviews before the full-resolution data (the COG layout) only when it copies
    a finished file, so products written tile by tile go through a scratch file. It is written
    uncompressed: the overviews are then built without decoding blocks, and the only
    compression is the copy's. The scratch file is always removed.
    """
    creation = {k: v for k, v in profile.items() if k in _COG_OPTIONS}
    scratch_profile = {k: v for k, v in profile.items()
                       if k not in ("compress", "predictor", "zlevel", "num_threads")}
    scratch_profile["compress"] = "none"
    with atomic_output(path, tag=False) as final:
        scratch = final.with_name(f"{final.stem}.scratch{final.suffix}")
        # tagged before the copy (as it is created): rewriting a COG would spoil its layout
        product = _product_of_file(Path(path))
        try:
            with _tagged_on_create(scratch, product):
                yield scratch, scratch_profile
            gdal_copy(str(scratch), str(final), driver="GTiff", copy_src_overviews=True, **creation)
        finally:
            _remove_with_sidecars(scratch)


@contextlib.contextmanager
def staged_folder(path: PathLike, replace: bool = False, product: str = "") -> Iterator[Path]:
    """Yield a temporary folder beside ``path``; rename it to ``path`` only on success.

    Parameters
    ----------
    path : path
        The output folder.
    replace : bool
        Allow replacing an existing folder of that name (after success) — but only an earlier
        product of the same algorithm (its :data:`PRODUCT_MARKER` names ``product``): an
        operator's own folder, another algorithm's product and a project are never deleted.
    product : str
        What is written (the algorithm id; default: the current run's), recorded in the marker
        file. A folder that holds ``project.toml`` gets no marker: a project is never a product
        that a later run may replace.

    Raises
    ------
    InputError
        Before any work is done, when ``path`` exists, is not empty and may not be replaced.
    """
    path = Path(path)
    product = product or output_policy.current_product()
    _check_staged_target(path, replace, product)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temp_sibling(path)
    tmp.mkdir()
    try:
        yield tmp
        if not (tmp / output_policy.PROJECT_FILE).exists():
            output_policy.write_marker(tmp, product, time.strftime("%Y-%m-%dT%H:%M:%S"))
        _swap_in(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _check_staged_target(path: Path, replace: bool, product: str) -> None:
    """The second line of defence of :func:`staged_folder` (the first is the registry's)."""
    if path.exists() and not path.is_dir():
        raise InputError.of("The output '{path}' is a file, not a folder; choose a folder.",
                            path=path)
    if not (path.exists() and any(path.iterdir())):
        return
    if (path / output_policy.PROJECT_FILE).exists():
        raise InputError.of("The output folder '{path}' is a PhotoDEM project; choose "
                            "another folder (a project is never replaced).", path=path)
    if not replace:
        raise InputError.of(
            "The output folder '{path}' exists and is not empty; choose a new folder "
            "(PhotoDEM does not overwrite earlier results here).", path=path)
    found = output_policy.folder_product(path)
    if found is None or (product and found != product):
        what = (msg("a product of '{other}'", other=found) if found
                else msg("files PhotoDEM did not write"))
        raise InputError.of(
            "The output folder '{path}' holds {what}; choose an empty or new folder "
            "(PhotoDEM only replaces earlier results of the same algorithm).", path=path,
            what=what)


def _swap_in(tmp: Path, path: Path) -> None:
    """Rename ``tmp`` to ``path`` (moving an old ``path`` aside first) as one commit step.

    SIGINT is held back over both renames and the record, so an interrupt can never leave
    neither the old nor the new folder; the old one is deleted afterwards.
    """
    old: Optional[Path] = None
    with output_policy.sigint_blocked():
        if path.exists():
            old = _temp_sibling(path, "old")
            os.replace(path, old)
        os.replace(tmp, path)
        output_policy.commit(path)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def scratch_folder(folder: PathLike, label: str) -> Iterator[Path]:
    """A hidden work folder in ``folder`` named after this process; removed afterwards.

    Named like a staged output (``.<label>.<pid>.<random>.partial``), so that the one of a
    killed run is removed by a later run writing there (:func:`..output_policy.remove_stale`).
    """
    path = Path(folder) / output_policy.staging_name(label)
    path.mkdir(parents=True)
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)


@contextlib.contextmanager
def open_image(path: PathLike, mode: str = "r", **profile: Any) -> Iterator[Any]:
    """``rasterio.open`` for rasters in image space (aerial images, epipolar images).

    Such rasters have no georeference on purpose, so rasterio's ``NotGeoreferencedWarning`` is
    noise there and is silenced; everything else is as ``rasterio.open``. A staged main
    GeoTIFF output of the run (see :func:`atomic_output`) gets its product tag as it is
    created.
    """
    product = _TAG_ON_CREATE.pop(os.fspath(path), "") if mode == "w" else ""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(path, mode, **profile) as dataset:
            if product:
                dataset.update_tags(**{PRODUCT_TAG: product})
            yield dataset


def write_raster(
    path: PathLike,
    data: NDArray[Any],
    transform: Optional[Affine] = None,
    crs: Any = None,
    nodata: Optional[float] = None,
    overviews: bool = False,
    **options: Any,
) -> Path:
    """Write a 2-D (rows, cols) or 3-D (bands, rows, cols) array as a tiled GeoTIFF, atomically.

    Without ``transform`` the raster lives in image space (pixel coordinates). Float rasters
    default to ``nodata = NaN``. ``overviews=True`` writes a Cloud-Optimised GeoTIFF with
    internal overviews
    (factors 2, 4, 8, … down to ~256 px) for display.
    """
    arr = np.asarray(data)
    if arr.ndim == 2:
        arr = arr[None]
    count, height, width = arr.shape
    if nodata is None and np.issubdtype(arr.dtype, np.floating):
        nodata = float("nan")
    extra: Dict[str, Any] = {} if transform is None else {"transform": transform}
    if np.issubdtype(arr.dtype, np.floating):
        extra["predictor"] = 3
    profile = gtiff_profile(width, height, count, arr.dtype.name, crs, nodata=nodata,
                            **{**extra, **options})
    if not overviews:
        with atomic_output(path) as tmp, open_image(tmp, "w", **profile) as dst:
            dst.write(arr)
        return Path(path)
    with cog_output(path, profile) as (tmp, scratch), open_image(tmp, "w", **scratch) as dst:
        dst.write(arr)
        factors = overview_factors(width, height)
        if factors:
            dst.build_overviews(factors, Resampling.average)
    return Path(path)


def overview_factors(width: int, height: int) -> List[int]:
    """Internal overview factors 2, 4, 8, … of a raster, down to about 256 cells on the
    longer side (a level smaller than one 256-cell block is not worth reading)."""
    factors, f = [], 2
    while max(width, height) / f >= 256:
        factors.append(f)
        f *= 2
    return factors
