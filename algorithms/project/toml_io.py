"""Reading and writing ``project.toml``.

Reading uses the standard library's ``tomllib`` (``tomli`` before Python 3.11). Writing needs
only what project files hold — tables, arrays of tables, strings, numbers, booleans and arrays
of those — so a small writer here saves a dependency.
"""

from __future__ import annotations

import math
import sys
from typing import Any, Dict, List

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.9/3.10 only
    import tomli as tomllib


def loads(text: str) -> Dict[str, Any]:
    """Parse TOML text."""
    return tomllib.loads(text)


def dumps(data: Dict[str, Any]) -> str:
    """Serialise a dict of tables, arrays of tables and scalars to TOML."""
    lines: List[str] = []
    _write_table(lines, [], data)
    return "\n".join(lines).strip() + "\n"


def _write_table(lines: List[str], path: List[str], table: Dict[str, Any]) -> None:
    scalars = {k: v for k, v in table.items() if not _is_table(v) and not _is_table_array(v)}
    for key, value in scalars.items():
        if value is None:
            continue
        lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in table.items():
        if _is_table(value):
            lines.append("")
            lines.append("[" + ".".join(_key(k) for k in [*path, key]) + "]")
            _write_table(lines, [*path, key], value)
        elif _is_table_array(value):
            for item in value:
                lines.append("")
                lines.append("[[" + ".".join(_key(k) for k in [*path, key]) + "]]")
                _write_table(lines, [*path, key], item)


def _is_table(value: Any) -> bool:
    return isinstance(value, dict)


def _is_table_array(value: Any) -> bool:
    return isinstance(value, list) and len(value) > 0 and all(isinstance(v, dict) for v in value)


def _key(key: str) -> str:
    if key and all(c.isalnum() or c in "-_" for c in key):
        return key
    return _string(key)


def _string(text: str) -> str:
    escaped = (text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
               .replace("\t", "\\t").replace("\r", "\\r"))
    return f'"{escaped}"'


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        text = repr(value)
        return text if any(c in text for c in ".en") else text + ".0"
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if hasattr(value, "item"):  # numpy scalar
        return _value(value.item())
    raise TypeError(f"cannot write {type(value).__name__} to TOML")
