"""How reports name the files they compare.

A report read later, or beside another one, must say *which* ``dtm.tif`` it compared: file
names alone repeat in every model folder. :func:`report_path` gives the project-relative path
of a file inside a PhotoDEM project (``<project folder>/products/…``) and the absolute path
otherwise; :func:`distinct_names` gives short column names that still tell files apart.
"""

from __future__ import annotations

from pathlib import Path
from typing import List, Sequence, Union

from ..output_policy import project_root

PathLike = Union[str, Path]


def report_path(path: PathLike) -> str:
    """The name of ``path`` as a report shows it.

    Parameters
    ----------
    path : path
        A file.

    Returns
    -------
    str
        ``<project folder name>/<path inside the project>`` when the file lies in a PhotoDEM
        project (a folder with ``project.toml`` at or above it), else the absolute path; always
        with forward slashes.

    Examples
    --------
    >>> report_path("/nowhere/dtm.tif")
    '/nowhere/dtm.tif'
    """
    p = Path(path).expanduser().absolute()
    root = project_root(p.parent)
    if root is None:
        return p.as_posix()
    return (Path(root.name) / p.relative_to(root)).as_posix()


def distinct_names(paths: Sequence[PathLike]) -> List[str]:
    """Short names that tell ``paths`` apart: the file stem, with as many parent folders as
    needed to make every name unique (``m1/dtm``, ``m2/dtm``).

    The same path listed twice gets ``_2``, ``_3`` … suffixes.

    Examples
    --------
    >>> distinct_names(["/a/m1/dtm.tif", "/a/m2/dtm.tif", "/a/m1/dsm.tif"])
    ['m1/dtm', 'm2/dtm', 'dsm']
    """
    full = [Path(p).expanduser().absolute().with_suffix("") for p in paths]
    parts = [f.parts[1:] if f.anchor else f.parts for f in full]
    depth = [1] * len(parts)
    while True:
        names = ["/".join(pp[-d:]) or "dem" for pp, d in zip(parts, depth)]
        clash = [i for i, n in enumerate(names) if depth[i] < len(parts[i]) and any(
            m == n and parts[j] != parts[i] for j, m in enumerate(names))]
        if not clash:
            break
        for i in clash:
            depth[i] += 1
    out: List[str] = []
    for name in names:
        base, k = name, 2
        while name in out:
            name, k = f"{base}_{k}", k + 1
        out.append(name)
    return out


__all__ = ["distinct_names", "report_path"]
