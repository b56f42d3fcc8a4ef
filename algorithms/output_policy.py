"""Where a run may write, and what it has already committed.

One rule for every output, checked by :func:`check_targets` before the first computation of a
run (``processing.registry.run`` calls it for every face):

- an existing output (file or folder) is replaced only by a product of the **same algorithm**:
  folders carry :data:`PRODUCT_MARKER` (``{"product": <algorithm id>}``), GeoTIFFs the metadata
  tag :data:`PRODUCT_TAG`; a sidecar file (a report beside a raster) may be replaced only
  together with the product it belongs to;
- never a project (a folder holding ``project.toml``), anything that contains one, or a
  project's own files (``project.toml``, ``edits.gpkg``, ``images/``, ``.photodem/``, its
  images);
- never a path that is, or contains, an input of the run;
- a derived default stays inside the folder it is derived from (:func:`contained`);
- a folder where a file is expected (and vice versa), the working folder itself, or a parent
  that is a file is refused.

The second half of this module is the *run scope*: staging names carry the process id
(:func:`staging_name`), leftovers of dead processes are removed (:func:`remove_stale`), and
every final rename is recorded (:func:`commit`) so that a late cancellation cannot claim that
nothing was written. This module is the ground floor: it imports only the standard library and
:mod:`.errors`.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import struct
import threading
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, Iterable, Iterator, List, Optional, Sequence, Union

from .errors import InputError, Message, msg

PathLike = Union[str, Path]

#: Marker file in every folder a PhotoDEM algorithm wrote (``{"product": <algorithm id>}``).
PRODUCT_MARKER = ".photodem-product.json"
#: GeoTIFF metadata item naming the algorithm that wrote a raster product.
PRODUCT_TAG = "PHOTODEM_PRODUCT"
#: The file that makes a folder a project.
PROJECT_FILE = "project.toml"
#: Names inside a project folder that no output may be or lie in.
PROJECT_PARTS = (PROJECT_FILE, "edits.gpkg", "images", ".photodem")

#: ``.<name>.<pid>.<8 hex>.<kind>[<suffix…>]``: staged outputs and folders moved aside.
_STAGING = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.(?P<tag>[0-9a-f]{8})"
                      r"\.(?P<kind>partial|old)(?P<rest>\..*)?$")


# -- targets -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Target:
    """One path a run will write.

    Parameters
    ----------
    path : Path
        The final path.
    kind : {"file", "folder"}
        What will be there.
    name : str
        The parameter or output it comes from (named in messages).
    owner : Path, optional
        For a sidecar file: the product it belongs to; it may be replaced when that one may.
    reuse : bool
        A folder that is written into but never replaced (a batch's run folder): what it
        holds already stays, so the rule on existing outputs does not apply; all others do.
    """

    path: Path
    kind: str = "file"
    name: str = "output"
    owner: Optional[Path] = None
    reuse: bool = False


def contained(path: PathLike, folder: PathLike, what: str) -> Path:
    """``path`` resolved, after checking that it lies inside ``folder``.

    Raises
    ------
    InputError
        When a name (e.g. a stereo model called ``../../x``) leads outside ``folder``.
    """
    resolved, base = Path(path).resolve(), Path(folder).resolve()
    if resolved == base or base not in resolved.parents:
        raise InputError.of("{what} leads to '{path}', outside '{folder}'; rename it (names "
                            "may not contain '/', '\\' or '..').", what=what, path=path,
                            folder=folder)
    return Path(path)


# -- product marks -------------------------------------------------------------------------------
def folder_product(folder: PathLike) -> Optional[str]:
    """The algorithm id in a folder's :data:`PRODUCT_MARKER`, or ``None``."""
    return folder_product_file(Path(folder) / PRODUCT_MARKER)


def folder_product_file(marker: Path) -> Optional[str]:
    """The ``product`` of a marker file, or ``None`` (missing or unreadable)."""
    try:
        data = json.loads(marker.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    product = data.get("product") if isinstance(data, dict) else None
    return str(product) if product else None


def write_marker(folder: PathLike, product: str, written: str,
                 name: str = PRODUCT_MARKER) -> None:
    """Write a product marker (default :data:`PRODUCT_MARKER`) into ``folder``."""
    text = json.dumps({"product": product, "written": written})
    (Path(folder) / name).write_text(text, encoding="utf-8")


def file_mark(path: PathLike) -> Path:
    """The hidden mark ``.<name>.photodem-product.json`` of a file product that is no GeoTIFF
    (a GeoTIFF carries :data:`PRODUCT_TAG` inside instead)."""
    path = Path(path)
    return path.with_name(f".{path.name}.photodem-product.json")


def is_tiff(path: PathLike) -> bool:
    """True for ``.tif`` / ``.tiff`` names (products that carry the tag inside)."""
    return Path(path).suffix.lower() in (".tif", ".tiff")


def file_product(path: PathLike) -> Optional[str]:
    """The algorithm that wrote a file product: a GeoTIFF's :data:`PRODUCT_TAG` (read from
    its first directory), another file's :func:`file_mark`; ``None`` if none.

    Pure Python on purpose: a check before the run must not depend on GDAL or fail on a
    corrupt file (a file that cannot be read is simply not a product).
    """
    if not is_tiff(path):
        return folder_product_file(file_mark(path))
    try:
        xml = _gdal_metadata(Path(path))
    except (OSError, struct.error, ValueError):
        return None
    if not xml:
        return None
    match = re.search(r'<Item name="' + PRODUCT_TAG + r'"[^>]*>([^<]*)</Item>', xml)
    return match.group(1).strip() if match else None


def _gdal_metadata(path: Path) -> Optional[str]:
    """The GDAL_METADATA tag (42112) of the first directory of a (Big)TIFF."""
    with open(path, "rb") as fh:
        head = fh.read(16)
        if head[:2] not in (b"II", b"MM"):
            return None
        end = "<" if head[:2] == b"II" else ">"
        magic = struct.unpack(end + "H", head[2:4])[0]
        if magic == 42:
            offset = struct.unpack(end + "I", head[4:8])[0]
            count_fmt, entry_fmt, entry_size, inline = "H", "HHII", 12, 4
        elif magic == 43:
            offset = struct.unpack(end + "Q", head[8:16])[0]
            count_fmt, entry_fmt, entry_size, inline = "Q", "HHQQ", 20, 8
        else:
            return None
        fh.seek(offset)
        size = struct.calcsize(end + count_fmt)
        (count,) = struct.unpack(end + count_fmt, fh.read(size))
        if count > 4096:
            return None
        entries = fh.read(count * entry_size)
        for i in range(count):
            tag, typ, n, value = struct.unpack(end + entry_fmt,
                                               entries[i * entry_size:(i + 1) * entry_size])
            if tag != 42112 or typ != 2:
                continue
            if n <= inline:
                raw = entries[i * entry_size + entry_size - inline:][:n]
            else:
                fh.seek(value)
                raw = fh.read(min(n, 1 << 20))
            return raw.decode("utf-8", "replace")
    return None


def _is_product(path: Path, algorithm: str) -> bool:
    if path.is_dir():
        return folder_product(path) == algorithm
    return file_product(path) == algorithm


# -- the output policy ---------------------------------------------------------------------------
def project_root(path: Path) -> Optional[Path]:
    """The nearest folder at or above ``path`` that holds ``project.toml``, or ``None``."""
    for folder in (path, *path.parents):
        if (folder / PROJECT_FILE).is_file():
            return folder
    return None


def _holds_project(folder: Path, limit: int = 20000) -> bool:
    """True when ``folder`` or a folder below it holds ``project.toml`` (``limit`` entries)."""
    seen = 0
    for _root, dirs, files in os.walk(folder):
        if PROJECT_FILE in files:
            return True
        seen += len(dirs) + len(files)
        if seen > limit:
            return False
    return False


def check_targets(algorithm: str, targets: Sequence[Target], inputs: Iterable[PathLike] = (),
                  protected: Iterable[PathLike] = ()) -> None:
    """Refuse any target the output policy forbids (see the module docstring).

    Parameters
    ----------
    algorithm : str
        Id of the algorithm that will write.
    targets : sequence of Target
        Every path the run will write.
    inputs : paths
        Input files and folders of the run.
    protected : paths
        Further files no output may be or contain (e.g. the images of a project input).

    Raises
    ------
    InputError
        One line naming the parameter, the path and what to do.
    """
    inputs_r = [Path(p).resolve() for p in inputs]
    protected_r = [Path(p).resolve() for p in protected]
    cwd = Path.cwd().resolve()
    for target in targets:
        out = target.path.resolve()
        label = msg("Parameter '{name}': the output '{path}'", name=target.name,
                    path=target.path)
        if out == cwd or out == Path(out.anchor) or out == Path.home().resolve():
            raise InputError.of("{label} is the working, home or root folder; name a new folder "
                                "or file inside it.", label=label)
        _check_parent(out, label)
        _check_kind(out, target.kind, label)
        _check_project(out, label)
        for inp in inputs_r + protected_r:
            if out == inp or out in inp.parents:
                raise InputError.of("{label} is or contains the input '{input}'; PhotoDEM "
                                    "never overwrites its inputs. Choose another output.",
                                    label=label, input=inp)
        if not target.reuse:
            _check_existing(out, target, algorithm, label)


def _check_parent(out: Path, label: Message) -> None:
    for parent in out.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError.of("{label} lies below '{parent}', which is a file; choose "
                                    "a path in a folder.", label=label, parent=parent)
            return


def _check_kind(out: Path, kind: str, label: Message) -> None:
    if kind == "file" and out.is_dir():
        raise InputError.of("{label} is a folder, but a file is expected; give a file name.",
                            label=label)
    if kind == "folder" and out.exists() and not out.is_dir():
        raise InputError.of("{label} is a file, but a folder is expected; give a folder name.",
                            label=label)


def _check_project(out: Path, label: Message) -> None:
    if out.is_dir() and _holds_project(out):
        raise InputError.of("{label} is or contains a PhotoDEM project; choose a folder "
                            "outside it (e.g. below its products/ folder).", label=label)
    root = project_root(out.parent)
    if root is not None:
        rel = out.relative_to(root)
        if rel.parts and rel.parts[0] in PROJECT_PARTS:
            raise InputError.of("{label} is part of the project '{root}' ({part}); write "
                                "products below its products/ folder.", label=label, root=root,
                                part=rel.parts[0])


def _check_existing(out: Path, target: Target, algorithm: str, label: Message) -> None:
    if not out.exists():
        return
    if out.is_dir():
        if not any(out.iterdir()) or folder_product(out) == algorithm:
            return
        other = folder_product(out)
        what = (msg("a product of '{other}'", other=other) if other
                else msg("files PhotoDEM did not write"))
        raise InputError.of("{label} holds {what}; only an earlier '{algorithm}' result is "
                            "replaced. Choose an empty or new folder.", label=label, what=what,
                            algorithm=algorithm)
    if target.owner is not None:
        owner = target.owner.resolve()
        if owner.exists() and _is_product(owner, algorithm):
            return
        raise InputError.of("{label} exists and does not belong to an earlier '{algorithm}' "
                            "result '{owner}'; move it or choose another output name.",
                            label=label, algorithm=algorithm, owner=target.owner)
    other = file_product(out)
    if other == algorithm:
        return
    what = (msg("a product of '{other}'", other=other) if other
            else msg("a file PhotoDEM did not write"))
    raise InputError.of("{label} exists and is {what}; only an earlier '{algorithm}' result is "
                        "replaced. Choose another file name.", label=label, what=what,
                        algorithm=algorithm)


# -- staging names and leftovers -----------------------------------------------------------------
def staging_name(name: str, kind: str = "partial", suffix: str = "") -> str:
    """A hidden sibling name owned by this process: ``.<name>.<pid>.<random>.<kind><suffix>``."""
    return f".{name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.{kind}{suffix}"


def pid_alive(pid: int, start: Optional[str] = None) -> bool:
    """True when process ``pid`` runs (and, if ``start`` is given, started then: a reused pid
    is another process). A process that cannot be asked is assumed alive: leftovers and locks
    of a live process must never be taken."""
    if pid <= 0 or pid == os.getpid():
        return True
    if os.name == "nt":  # os.kill with signal 0 would end the process there
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # EPERM: it runs under another user
        return True
    fields = _process_stat(pid)
    if fields is None:
        return True
    if fields[0] == "Z":  # a zombie has ended
        return False
    return start is None or len(fields) <= 19 or fields[19] == start


def process_start(pid: int) -> Optional[str]:
    """The start time of a process in clock ticks since boot (Linux), to tell a reused pid."""
    fields = _process_stat(pid)
    return fields[19] if fields and len(fields) > 19 else None


def _process_stat(pid: int) -> Optional[List[str]]:
    """Fields of ``/proc/<pid>/stat`` after the command name (Linux), else None."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    return text.rsplit(")", 1)[-1].split()


def stale_leftovers(folder: PathLike) -> List[tuple]:
    """``(path, pid)`` of the staging leftovers in ``folder`` whose process is gone."""
    folder = Path(folder)
    found = []
    try:
        entries = list(folder.iterdir())
    except OSError:
        return []
    for entry in entries:
        match = _STAGING.match(entry.name)
        if match and not pid_alive(int(match.group("pid"))):
            found.append((entry, int(match.group("pid"))))
    return found


def remove_stale(folders: Iterable[PathLike],
                 report: Optional[Callable[[str], None]] = None) -> List[Path]:
    """Remove staging leftovers of dead processes in ``folders``; say so through ``report``.

    Leftovers of running processes (another run writing there now) are left alone.
    """
    removed: List[Path] = []
    for folder in dict.fromkeys(Path(f) for f in folders):
        for path, pid in stale_leftovers(folder):
            try:
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path)
                else:
                    path.unlink()
            except FileNotFoundError:
                continue
            except OSError:
                continue
            removed.append(path)
            if report is not None:
                report(f"Removed the leftover '{path}' of process {pid}, no longer running.")
    return removed


# -- the run scope -------------------------------------------------------------------------------
@dataclass
class RunScope:
    """What one run writes: its algorithm id and the outputs it has committed so far."""

    product: str
    committed: List[Path] = field(default_factory=list)
    on_commit: Optional[Callable[[Path], None]] = None
    #: Resolved paths of the run's outputs; empty when unknown (a direct call).
    targets: Dict[Path, Target] = field(default_factory=dict)

    def is_target(self, path: PathLike) -> bool:
        """True when ``path`` is one of the run's outputs (any path, when they are unknown)."""
        return not self.targets or Path(path).resolve() in self.targets

    def is_product_file(self, path: PathLike) -> bool:
        """True when ``path`` is a main file output of the run (it carries the product tag)."""
        target = self.targets.get(Path(path).resolve())
        return target is not None and target.kind == "file" and target.owner is None


_LOCAL = threading.local()
_ACTIVE: List[RunScope] = []
_ACTIVE_LOCK = threading.Lock()


@contextlib.contextmanager
def run_scope(product: str, on_commit: Optional[Callable[[Path], None]] = None,
              targets: Sequence[Target] = ()) -> Iterator[RunScope]:
    """Open the scope of one run of ``product`` in this thread (nested scopes stack).

    ``targets``: the outputs the run writes (as checked by :func:`check_targets`); only their
    renames count as commits, and only main file outputs get the product tag.
    """
    scope = RunScope(product, on_commit=on_commit,
                     targets={t.path.resolve(): t for t in targets})
    stack = _stack()
    stack.append(scope)
    with _ACTIVE_LOCK:
        _ACTIVE.append(scope)
    try:
        yield scope
    finally:
        stack.pop()
        with _ACTIVE_LOCK:
            _ACTIVE.remove(scope)


def _stack() -> List[RunScope]:
    if not hasattr(_LOCAL, "stack"):
        _LOCAL.stack = []
    return _LOCAL.stack


def current() -> Optional[RunScope]:
    """The scope of the run in this thread; in a helper thread, the only active one, if any."""
    stack = _stack()
    if stack:
        return stack[-1]
    with _ACTIVE_LOCK:
        return _ACTIVE[0] if len(_ACTIVE) == 1 else None


def current_product() -> str:
    """The algorithm id of the current run, ``""`` outside a run."""
    scope = current()
    return scope.product if scope is not None else ""


def commit(path: PathLike) -> None:
    """Record that ``path`` is now final (called right after its rename)."""
    scope = current()
    if scope is None or not scope.is_target(path):
        return
    scope.committed.append(Path(path))
    if scope.on_commit is not None:
        scope.on_commit(Path(path))


def committed() -> bool:
    """True once the current run has committed an output."""
    scope = current()
    return bool(scope is not None and scope.committed)


@contextlib.contextmanager
def sigint_blocked() -> Iterator[None]:
    """Hold back SIGINT (delivered afterwards) so that a rename and its record stay one step.

    Only the main thread receives Python's signal handlers, so only there is anything held
    back; elsewhere, and without ``pthread_sigmask`` (Windows), this does nothing.
    """
    can = hasattr(signal, "pthread_sigmask") and \
        threading.current_thread() is threading.main_thread()
    if not can:
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


__all__ = [
    "PRODUCT_MARKER",
    "PRODUCT_TAG",
    "PROJECT_FILE",
    "RunScope",
    "Target",
    "check_targets",
    "commit",
    "committed",
    "contained",
    "current",
    "current_product",
    "file_mark",
    "file_product",
    "folder_product",
    "is_tiff",
    "pid_alive",
    "project_root",
    "remove_stale",
    "run_scope",
    "sigint_blocked",
    "staging_name",
    "stale_leftovers",
    "write_marker",
]
