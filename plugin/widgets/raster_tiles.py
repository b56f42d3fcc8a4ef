"""Rasters on the standalone map: tiles from the overviews, drawn off the GUI thread, cached.

A :class:`RasterLayer` cuts the view into 256 × 256 tiles of the zoom level that fits
(:class:`~photodem.algorithms.raster.display.TileGrid`: a fixed grid per level, so a pan
reuses the tiles it has). A missing tile is read and coloured in a ``QThreadPool`` (each job
borrows a dataset handle of its own: rasterio handles are not thread-safe) and delivered by a
queued signal to the GUI thread, where it goes into an LRU cache bounded by bytes
(:data:`CACHE_BYTES`). Until it arrives, the tile of a coarser level is drawn scaled, so a
zoom never shows a blank. A job whose tile has left the view before it starts is dropped.

Reading and colouring are Qt-free (:mod:`photodem.algorithms.raster.display`).
"""

from __future__ import annotations

import os
import threading
import time
from collections import OrderedDict
from pathlib import Path
from typing import Any, FrozenSet, List, Optional, Set, Tuple

from ...algorithms.errors import InputError
from ...algorithms.feedback import Feedback
from ...algorithms.project.products import classify
from ...algorithms.raster import display
from ..i18n import tr
from ..qt import QtCore, QtGui, pyqtSignal
from .map_layer import Bounds, MapLayer, ViewState

#: Bytes of tiles kept by all raster layers together (LRU).
CACHE_BYTES = 128 * 1024 * 1024
Key = Tuple[int, int, int]


class TileCache:
    """Least-recently-used images bounded by their size in bytes (GUI thread only)."""

    def __init__(self, max_bytes: int = CACHE_BYTES) -> None:
        self.max_bytes = int(max_bytes)
        self.nbytes = 0
        self._items: OrderedDict[Any, QtGui.QImage] = OrderedDict()

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key: Any) -> bool:
        return key in self._items

    def get(self, key: Any) -> Optional[QtGui.QImage]:
        image = self._items.get(key)
        if image is not None:
            self._items.move_to_end(key)
        return image

    def put(self, key: Any, image: QtGui.QImage) -> None:
        """Keep ``image``; evict the least recently used ones beyond :attr:`max_bytes`."""
        self.discard(key)
        self._items[key] = image
        self.nbytes += image.sizeInBytes()
        while self.nbytes > self.max_bytes and len(self._items) > 1:
            _, old = self._items.popitem(last=False)
            self.nbytes -= old.sizeInBytes()

    def discard(self, key: Any) -> None:
        old = self._items.pop(key, None)
        if old is not None:
            self.nbytes -= old.sizeInBytes()

    def drop(self, owner: int) -> None:
        """Forget every tile of one layer (keys are ``(owner, …)``)."""
        for key in [k for k in self._items if k[0] == owner]:
            self.discard(key)


#: The cache shared by every raster layer of the process.
CACHE = TileCache()
_POOL: Optional[QtCore.QThreadPool] = None


def thread_pool() -> QtCore.QThreadPool:
    """The pool that renders tiles (2–4 threads; reading is mostly GDAL, which frees the GIL)."""
    global _POOL
    if _POOL is None:
        _POOL = QtCore.QThreadPool()
        _POOL.setMaxThreadCount(max(2, min(4, os.cpu_count() or 2)))
    return _POOL


class _Source:
    """What the render jobs of one layer share: the file, its grid and style, free handles.

    Thread-safe: jobs borrow a dataset handle (:meth:`acquire`) and give it back; ``wanted``
    is replaced (never mutated) by the GUI thread, so jobs read a consistent set.
    """

    def __init__(self, path: Path, info: display.RasterInfo, style: display.Style,
                 grid: display.TileGrid, map_crs: str) -> None:
        self.path, self.info, self.style, self.grid, self.map_crs = (path, info, style, grid,
                                                                      map_crs)
        self.wanted: FrozenSet[Key] = frozenset()
        self.closed = False
        self._free: List[Any] = []
        self._lock = threading.Lock()

    def acquire(self) -> Any:
        with self._lock:
            if self._free:
                return self._free.pop()
        return display.open_raster(self.path)

    def release(self, handle: Any) -> None:
        with self._lock:
            if not self.closed:
                self._free.append(handle)
                return
        handle.close()

    def close(self) -> None:
        with self._lock:
            self.closed = True
            free, self._free = self._free, []
        for handle in free:
            handle.close()

    def render(self, key: Key) -> Optional[QtGui.QImage]:
        """The tile as an image (None: dropped, or the read failed)."""
        if self.closed or key not in self.wanted:
            return None
        handle = self.acquire()
        try:
            rgba = display.render_tile(handle, self.info, self.grid, self.style, key,
                                       self.map_crs)
        finally:
            self.release(handle)
        h, w = rgba.shape[:2]
        return QtGui.QImage(rgba.tobytes(), w, h, 4 * w, QtGui.QImage.Format_RGBA8888).copy()


class _Signals(QtCore.QObject):
    """Carries finished tiles to the GUI thread (queued: it lives there)."""

    done = pyqtSignal(object, object, object)  # source, key, QImage or None


class _TileJob(QtCore.QRunnable):
    def __init__(self, source: _Source, key: Key, signals: _Signals) -> None:
        super().__init__()
        self.source, self.key, self.signals = source, key, signals
        self.setAutoDelete(True)

    def run(self) -> None:
        try:
            image = self.source.render(self.key)
        except Exception:  # a broken tile must not end the thread; it stays missing
            image = None
        self.signals.done.emit(self.source, self.key, image)


class RasterLayer(MapLayer):
    """A raster file on the map (see the module docstring).

    Parameters
    ----------
    path : path
        The raster (GeoTIFF or anything GDAL reads).
    kind : str
        ``dsm``, ``dtm``, ``difference``, ``ortho``, ``mosaic``, ``image`` or ``auto``
        (the project's product kind, else from the bands: see
        :func:`~photodem.algorithms.raster.display.guess_kind`).
    name : str
        Shown in the layer list (default: the product's kind and name, or the file's stem).
    map_crs : str
        The map's CRS (WKT or ``EPSG:n``); a raster in another CRS is reprojected tile by tile.
        The view's CRS replaces it when it differs.

    Raises
    ------
    InputError
        GDAL cannot open the file (the message names it).
    """

    def __init__(self, path: Any, kind: str = "auto", name: str = "", map_crs: str = "",
                 parent: Optional[QtCore.QObject] = None) -> None:
        path = Path(path)
        with display.open_raster(path) as src:
            info = display.raster_info(src)
            kind, default_name = _kind_and_name(path, info, kind)
            style = display.make_style(src, info, kind)
        super().__init__(name or default_name, kind, path, parent)
        self.info = info
        self._owner = id(self)
        self._signals = _Signals()
        self._signals.done.connect(self._tile_done)
        self._pending: Set[Key] = set()
        self._value_handle: Any = None
        self._source = self._make_source(style, map_crs if info.has_crs else "")

    # -- public ---------------------------------------------------------------------------------
    @property
    def has_crs(self) -> bool:
        """False: the layer is in pixel coordinates (x = col, y = −row)."""
        return self.info.has_crs

    @property
    def needs_overviews(self) -> bool:
        """Larger than 2048 pixels and without overviews: slow to draw until they are built."""
        return self.info.needs_overviews

    @property
    def map_crs(self) -> str:
        return self._source.map_crs

    def bounds(self) -> Optional[Bounds]:
        g = self._source.grid
        x0, y1 = g.origin
        return x0, y1 - g.res[1] * g.size[1], x0 + g.res[0] * g.size[0], y1

    def build_overviews(self, feedback: Optional[Feedback] = None) -> Path:
        """Write overviews into the raster's ``.ovr`` sidecar (the raster itself is untouched),
        then draw from them.

        Raises
        ------
        InputError
            The folder is read-only or an ``.ovr`` exists already.
        """
        target = display.build_external_overviews(self.path, feedback)
        with display.open_raster(self.path) as src:
            self.info = display.raster_info(src)
        self._restart(self._source.style, self._source.map_crs)
        return target

    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        """Draw the cached tiles of the view, coarser ones where missing; request the rest."""
        self._follow_crs(view.crs)
        grid = self._source.grid
        level = grid.level_for(view.map_units_per_pixel)
        keys = [(level, c, r) for c, r in grid.tiles_in(view.extent, level)]
        self._source.wanted = frozenset(keys)
        painter.save()
        painter.setOpacity(painter.opacity() * self.opacity)
        painter.setRenderHint(QtGui.QPainter.SmoothPixmapTransform, True)
        for key in keys:
            image = CACHE.get((self._owner, key))
            if image is not None:
                _draw(painter, view, grid, key, image, (0, 0, display.TILE))
                continue
            self._request(key)
            self._draw_coarser(painter, view, grid, key)
        painter.restore()

    def value_at(self, x: float, y: float) -> Optional[str]:
        """``"<name>: 123.45 m"`` (DEM, difference), ``"<name>: R,G,B"``, ``"<name>: nodata"``;
        None outside the raster. Read at full resolution (one pixel)."""
        values = self.sample(x, y)
        if values is None:
            return None
        if any(v != v for v in values):
            return f"{self.name}: {tr('nodata')}"
        if self.kind in display.DEM_KINDS:
            return f"{self.name}: {values[0]:.2f} m"
        if self.kind == "difference":
            return f"{self.name}: {values[0]:+.2f} m"
        return f"{self.name}: " + ",".join(f"{v:g}" for v in values)

    def sample(self, x: float, y: float) -> Optional[List[float]]:
        """Band values at the map point (NaN = nodata), None outside the raster."""
        if self._value_handle is None:
            self._value_handle = display.open_raster(self.path)
        return display.read_value(self._value_handle, self.info, x, y, self._source.map_crs)

    def wait(self, timeout_ms: int = 5000) -> bool:
        """Process events until every tile of the last painted view is in (tests, benchmark)."""
        deadline = time.monotonic() + timeout_ms / 1000.0
        while self._pending & self._source.wanted:
            if time.monotonic() > deadline:
                return False
            QtCore.QCoreApplication.processEvents(QtCore.QEventLoop.AllEvents, 5)
            if self._pending & self._source.wanted:
                time.sleep(0.001)
        return True

    def missing(self) -> int:
        """Tiles of the last painted view not yet in the cache."""
        return sum((self._owner, k) not in CACHE for k in self._source.wanted)

    def close(self) -> None:
        """Drop pending work, free handles and this layer's tiles."""
        self._source.wanted = frozenset()
        self._source.close()
        CACHE.drop(self._owner)
        if self._value_handle is not None:
            self._value_handle.close()
            self._value_handle = None

    # -- internals ------------------------------------------------------------------------------
    def _make_source(self, style: display.Style, map_crs: str) -> _Source:
        grid = display.tile_grid(self.info, map_crs)
        return _Source(self.path, self.info, style, grid, map_crs)

    def _restart(self, style: display.Style, map_crs: str) -> None:
        """New grid or file: forget tiles and jobs of the old one."""
        self._source.close()
        CACHE.drop(self._owner)
        self._pending.clear()
        self._source = self._make_source(style, map_crs)
        self.changed.emit()

    def _follow_crs(self, view_crs: str) -> None:
        if self.info.has_crs and view_crs and view_crs != self._source.map_crs:
            self._restart(self._source.style, view_crs)

    def _request(self, key: Key) -> None:
        if key in self._pending:
            return
        self._pending.add(key)
        thread_pool().start(_TileJob(self._source, key, self._signals))

    def _tile_done(self, source: _Source, key: Key, image: Optional[QtGui.QImage]) -> None:
        if source is not self._source:
            return  # a job of a grid replaced since
        self._pending.discard(key)
        if image is not None:
            CACHE.put((self._owner, key), image)
            if key in source.wanted:
                self.changed.emit()

    def _draw_coarser(self, painter: QtGui.QPainter, view: ViewState,
                      grid: display.TileGrid, key: Key) -> None:
        """Draw the part of the nearest cached coarser tile that covers ``key``."""
        level, col, row = key
        for up in range(1, grid.levels - level):
            f = 2 ** up
            parent = (level + up, col // f, row // f)
            image = CACHE.get((self._owner, parent))
            if image is not None:
                size = display.TILE // f
                _draw(painter, view, grid, key, image,
                      ((col % f) * size, (row % f) * size, size))
                return


def _draw(painter: QtGui.QPainter, view: ViewState, grid: display.TileGrid, key: Key,
          image: QtGui.QImage, source: Tuple[int, int, int]) -> None:
    """Draw ``source`` (x, y, size in image pixels) of ``image`` onto the tile ``key``.

    The target corners are rounded to whole pixels the same way for neighbours, so tiles meet
    without gaps or overlaps.
    """
    x0, y0, x1, y1 = grid.tile_bounds(*key)
    p0 = view.to_pixel(x0, y1)
    p1 = view.to_pixel(x1, y0)
    left, top = round(p0.x()), round(p0.y())
    target = QtCore.QRect(left, top, round(p1.x()) - left, round(p1.y()) - top)
    sx, sy, size = source
    painter.drawImage(target, image, QtCore.QRect(sx, sy, size, size))


def _kind_and_name(path: Path, info: display.RasterInfo, kind: str) -> Tuple[str, str]:
    """The layer kind (``auto`` resolved) and its default name."""
    product = classify(path)
    if product is not None and product.kind != "seamlines":
        name = f"{product.kind.upper()} {product.name}"
        return (product.kind if kind == "auto" else kind), name
    return (display.guess_kind(info, path) if kind == "auto" else kind), path.stem


__all__ = ["CACHE", "CACHE_BYTES", "InputError", "RasterLayer", "TileCache", "thread_pool"]

