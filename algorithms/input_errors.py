"""One path from unreadable inputs to operator errors.

A damaged input (a truncated GeoTIFF, a GeoPackage that is not one, a TOML or YAML file with a
syntax error, a text file in another encoding) is something the operator fixes, so it must end
as an :class:`~.errors.InputError` naming the file and what is wrong — never as a traceback.

* :func:`operator_errors` wraps a whole run (``registry.run``): the exceptions of the file
  libraries (GDAL/rasterio, OGR/fiona, TOML, YAML, CSV, text decoding, file-system refusals)
  become one-line :class:`InputError`; everything else (an ``IndexError`` of numpy…) is a bug
  and passes unchanged.
* :func:`reading` does the same around the reading of one known file, so the message names it.
* :func:`check_raster` / :func:`check_rasters` are the cheap pre-flight check of raster inputs
  before any work: open the file and read the first and the last block of band 1 (a truncated
  TIFF fails on its last block).

This module imports only the standard library, the file libraries and :mod:`.errors`.
"""

from __future__ import annotations

import contextlib
import csv
import errno
import os
import sys
import threading
import warnings
from pathlib import Path
from typing import Any, Iterable, Iterator, List, Optional, Tuple, Type, Union

import rasterio
import rasterio.errors as rio
from rasterio._err import CPLE_FileIOError, CPLE_OpenFailedError
from rasterio.errors import NotGeoreferencedWarning, RasterioIOError
from rasterio.windows import Window

from .errors import InputError, Message, PhotodemError, msg

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.9/3.10 only
    import tomli as tomllib

PathLike = Union[str, Path]

#: Words of GDAL messages that mean the file's bytes are incomplete or garbled.
_DAMAGE_WORDS = ("TIFFRead", "TIFFFill", "Read error", "read failed", "Read failed",
                 "IReadBlock", "truncated", "corrupt", "Decode", "decode", "LZW", "Deflate",
                 "JPEGLib", "ZIPDecode")


def display_path(path: PathLike) -> str:
    """``path`` as text that can always be printed: bytes that are not UTF-8 (Python keeps them
    as surrogate escapes) are shown as ``\\xNN``."""
    text = os.fspath(path)
    if isinstance(text, bytes):
        text = os.fsdecode(text)
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def check_encodable(path: PathLike, what: str = "file") -> None:
    """Refuse a file name GDAL/OGR cannot be given.

    rasterio and fiona pass names to GDAL as UTF-8; a name whose bytes are not UTF-8 cannot be
    encoded and would fail with a codec error deep in the library.

    Raises
    ------
    InputError
        Naming the file and what to do.
    """
    try:
        os.fspath(path).encode("utf-8") if not isinstance(path, bytes) else path.decode("utf-8")
    except (UnicodeEncodeError, UnicodeDecodeError):
        raise _not_utf8_name(what, display_path(path)) from None


#: The roles of input files named in messages, as translatable phrases (German needs no
#: article after "als", so one template serves every role).
_ROLES = {m.template: m for m in (
    msg("file"), msg("raster"), msg("image"), msg("DEM"), msg("surface"), msg("output"),
    msg("vector file"), msg("text file"), msg("GeoPackage"), msg("project file"),
    msg("seamline file"))}


def role(what: str) -> Union[Message, str]:
    """``what`` (the role of a file: "raster", "image", …) as a translatable phrase when it is
    one of the known roles, else as it is."""
    return _ROLES.get(what, what)


def _not_utf8_name(what: str, name: str) -> InputError:
    """The error for a file name GDAL cannot be given."""
    return InputError.of("The {what} name '{name}' is not valid UTF-8 text; GDAL cannot open "
                         "it. Rename the file (or its folder) with UTF-8 characters only.",
                         what=role(what), name=name)


def _library_errors() -> Tuple[Type[BaseException], ...]:
    """The exception classes of the file libraries that mean "this input is unusable".

    Only classes raised while reading data are listed: a ``WindowError``, a ``SchemaError`` on
    writing or an ``InvalidArrayError`` is a programming error and stays one.
    """
    classes: List[Type[BaseException]] = [
        rio.RasterioIOError, rio.CRSError, rio.PathError, rio.FileError,
        CPLE_OpenFailedError, CPLE_FileIOError,
        UnicodeDecodeError, csv.Error,
    ]
    try:
        import fiona.errors as fio  # lazy: keeps photodem list fast

        names = ("DriverError", "DataIOError", "CRSError", "PathError",  # PathError: ≥ 1.10
                 "UnsupportedGeometryTypeError")
        classes += [getattr(fio, n) for n in names if hasattr(fio, n)]
    except ImportError:  # pragma: no cover - fiona is a dependency
        pass
    try:
        import yaml  # lazy: keeps photodem list fast

        classes.append(yaml.YAMLError)
    except ImportError:  # pragma: no cover
        pass
    classes.append(tomllib.TOMLDecodeError)
    return tuple(classes)


#: ``errno`` values of file-system refusals an operator fixes (rights, space, a folder where a
#: file is expected…).
_OPERATOR_ERRNOS = (errno.EACCES, errno.EPERM, errno.ENOSPC, errno.EISDIR, errno.ENOTDIR,
                    errno.ENOENT, errno.EROFS, errno.EDQUOT, errno.ENAMETOOLONG)


def _chain_messages(exc: BaseException) -> List[str]:
    """The messages of ``exc`` and its causes, innermost last, without repeats."""
    out: List[str] = []
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        text = " ".join(str(exc).split())
        if text and text not in out and not text.startswith("Read failed. See previous"):
            out.append(text)
        exc = exc.__cause__ or exc.__context__  # type: ignore[assignment]
    return out


def describe(exc: BaseException) -> str:
    """A one-line description of a library error, with a hint for damaged files."""
    if isinstance(exc, UnicodeDecodeError):
        return (f"it is not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at position "
                f"{exc.start}); save it as UTF-8")
    if isinstance(exc, tomllib.TOMLDecodeError):
        return f"TOML syntax error: {' '.join(str(exc).split())}"
    if isinstance(exc, UnicodeEncodeError):
        return "its name is not valid UTF-8 text; rename it"
    messages = _chain_messages(exc)
    # the two innermost messages say most (GDAL's call and its reason)
    text = ": ".join(m.rstrip(". ") for m in messages[-2:]) if messages else type(exc).__name__
    if len(text) > 240:
        text = text[:237] + "…"
    if any(word in text for word in _DAMAGE_WORDS):
        text += ": the file is truncated or damaged"
    return text


def _translate(exc: BaseException, path: Optional[PathLike], what: str) -> Optional[InputError]:
    """The :class:`InputError` for ``exc``, or ``None`` when it is not an operator's problem."""
    if isinstance(exc, PhotodemError):
        return None
    if isinstance(exc, UnicodeEncodeError) and "surrogates not allowed" in str(exc):
        name = display_path(path if path is not None else exc.object)
        if path is None and ("\n" in name or len(name) > 4096):  # a text, not a name
            return InputError.of("A file name that is not valid UTF-8 text could not be "
                                 "written into a report; rename the file with UTF-8 "
                                 "characters only.")
        return _not_utf8_name(what, name)
    if isinstance(exc, OSError) and exc.errno in _OPERATOR_ERRNOS:
        name = exc.filename if exc.filename is not None else path
        shown = (msg("'{path}'", path=display_path(name)) if name is not None
                 else msg("the {what}", what=role(what)))
        reason = exc.strerror or str(exc)  # the system's words (its own locale)
        return InputError.of("Cannot use {shown}: {reason}.", shown=shown, reason=reason)
    if isinstance(exc, _library_errors()):
        detail = describe(exc)  # GDAL's, OGR's or the parser's own words stay as they are
        if path is not None:
            return InputError.of("'{path}' is not a readable {what} ({detail}).",
                                 path=display_path(path), what=role(what), detail=detail)
        return InputError.of("An input file cannot be read ({detail}). Check the file it names "
                             "(replace a truncated or damaged copy).", detail=detail)
    return None


class InputWarning(UserWarning):
    """An input was repaired or is used with a restriction; the run goes on.

    Raised with :func:`warn_input` deep in the readers (which have no feedback); inside
    :func:`operator_errors` it goes to the run's feedback instead.
    """


#: The feedback of the run going on in this thread (set by :func:`operator_errors`). Thread-local,
#: not a swapped ``warnings.showwarning``: QGIS runs algorithms in threads side by side.
_RUN = threading.local()


def warn_input(message: str) -> None:
    """Tell the operator that an input was repaired or is used with a restriction: through the
    feedback of this thread's run, else as an :class:`InputWarning`."""
    feedback = getattr(_RUN, "feedback", None)
    if feedback is not None:
        feedback.warning(message)
    else:
        warnings.warn(message, InputWarning, stacklevel=2)


@contextlib.contextmanager
def operator_errors(feedback: Any = None) -> Iterator[None]:
    """Turn the file libraries' exceptions raised inside into :class:`InputError`.

    Used once around a whole run; programming errors pass through unchanged (with their
    traceback) so that they are found and fixed.

    Parameters
    ----------
    feedback : Feedback, optional
        Receives every :func:`warn_input` message of this thread inside (each one, also
        repeated ones) through its ``warning`` method; without one they are Python warnings.
    """
    outer = getattr(_RUN, "feedback", None)
    _RUN.feedback = feedback if feedback is not None else outer
    try:
        # inside a rasterio environment GDAL's messages go to Python's logging, not as extra
        # "ERROR 1: …" lines to stderr beside the one-line error
        with rasterio.Env():
            yield
    except Exception as exc:
        error = _translate(exc, None, "file")
        if error is None:
            raise
        raise error from exc
    finally:
        _RUN.feedback = outer


@contextlib.contextmanager
def reading(path: PathLike, what: str = "file") -> Iterator[None]:
    """Like :func:`operator_errors` for the reading of one file: the message names ``path``.

    Parameters
    ----------
    path : path
        The file read inside the block.
    what : str
        What it is ("raster", "vector file", "project file", …), for the message.
    """
    try:
        yield
    except Exception as exc:
        error = _translate(exc, path, what)
        if error is None:
            raise
        raise error from exc


def check_raster(path: PathLike, what: str = "raster") -> None:
    """Pre-flight check of a raster input: it opens and its first and last blocks of band 1
    decode (a truncated or damaged file fails here, before any work).

    A folder (a product folder given as input) is not checked here.

    Raises
    ------
    InputError
        Naming the file and what is wrong.
    """
    p = Path(path)
    if p.is_dir():
        return
    check_encodable(p, what)

    with reading(p, what), warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(p) as src:
            if src.count < 1 or src.width < 1 or src.height < 1:
                raise InputError.of("'{path}' is an empty raster (no band or no cells).",
                                    path=display_path(p))
            bh, bw = src.block_shapes[0]
            bw, bh = min(bw, src.width), min(bh, src.height)
            src.read(1, window=Window(0, 0, bw, bh))
            last_col = ((src.width - 1) // bw) * bw
            last_row = ((src.height - 1) // bh) * bh
            src.read(1, window=Window(last_col, last_row, min(bw, src.width - last_col),
                                      min(bh, src.height - last_row)))


def check_rasters(paths: Iterable[Optional[PathLike]], what: str = "raster") -> None:
    """:func:`check_raster` for each path given (``None`` entries are skipped)."""
    for path in paths:
        if path is not None:
            check_raster(path, what)


#: File endings of "file" parameters that are checked as rasters before a run (when GDAL
#: recognises them as rasters: such a parameter may also take points or text).
RASTER_SUFFIXES = (".tif", ".tiff", ".vrt", ".img", ".jp2", ".png", ".jpg", ".jpeg")


def check_raster_parameters(parameters: Iterable[object], values: dict) -> None:
    """Pre-flight check of every raster input of a run, before any work (and of the names of
    raster and vector outputs, which GDAL must be able to take).

    Parameters
    ----------
    parameters : iterable
        The algorithm's parameter declarations (objects with ``name`` and ``kind``).
    values : dict
        The prepared parameter values by name.

    Raises
    ------
    InputError
        Naming the parameter and the file that cannot be read.
    """
    for param in parameters:
        kind, name = getattr(param, "kind", ""), getattr(param, "name", "")
        value = values.get(name)
        if value is None:
            continue
        if kind in ("output_raster", "output_vector"):  # written by GDAL/OGR
            try:
                check_encodable(value, "output")
            except InputError as exc:
                raise InputError.of("Parameter '{name}': {error}", name=name, error=exc
                                    ) from None
            continue
        paths = list(value) if kind == "multiple_rasters" else [value]
        if kind == "file":
            paths = [p for p in paths if str(p).lower().endswith(RASTER_SUFFIXES)]
        elif kind not in ("raster", "multiple_rasters"):
            continue
        for path in paths:
            if kind == "file" and not _opens_as_raster(path):
                continue  # a "file" may be points or text: the algorithm decides
            try:
                check_raster(path)
            except InputError as exc:
                raise InputError.of("Parameter '{name}': {error}", name=name, error=exc
                                    ) from exc.__cause__


def _opens_as_raster(path: PathLike) -> bool:
    """True when GDAL recognises ``path`` as a raster (its blocks are not read)."""
    try:
        check_encodable(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            with rasterio.open(path):
                return True
    except (RasterioIOError, InputError):
        return False


def check_text_file(path: PathLike, what: str = "text file") -> str:
    """The content of a UTF-8 text input; an :class:`InputError` naming it when it cannot be
    read or is not UTF-8."""
    p = Path(path)
    with reading(p, what):
        return p.read_text(encoding="utf-8")


__all__ = [
    "RASTER_SUFFIXES",
    "InputWarning",
    "check_encodable",
    "check_raster",
    "check_raster_parameters",
    "check_rasters",
    "check_text_file",
    "describe",
    "display_path",
    "operator_errors",
    "reading",
    "role",
    "warn_input",
]
