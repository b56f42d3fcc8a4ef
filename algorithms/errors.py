"""Errors an operator can cause, and cancellation.

Every error an operator can fix (a missing file, no overlap, a wrong CRS, a bad parameter) is a
:class:`PhotodemError` whose message says what is wrong and what to do. The CLI prints it without
a traceback and exits 2; QGIS and the standalone tool show it in their log.

Messages the operator meets most are built with :meth:`PhotodemError.of` from an English
*template* and its *values*: ``str(exc)`` is the English sentence (CLI, logs), and the GUIs
translate the template (``plugin/i18n.py`` ``message_text``) and fill in the same values. The
core stays Qt-free; ``tools/update_translations.py`` finds the templates by the literal first
argument of ``<X>Error.of("…")`` and :func:`msg` calls.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, Optional


@dataclass(frozen=True)
class Message:
    """An English template with named values; ``str()`` is the English sentence.

    Values are shown with ``str.format`` (format specs such as ``{number:g}`` allowed); a value
    that is itself a :class:`Message` is a phrase the GUIs translate too. A template without
    values is shown as it is (it may be a text with braces, e.g. a parameter description).
    """

    template: str
    values: Dict[str, Any] = field(default_factory=dict)

    def __str__(self) -> str:
        return fill(self.template, self.values)

    def to_dict(self) -> Dict[str, Any]:
        """JSON-ready form (batch records): nested messages as dicts, other values that JSON
        cannot hold (paths) as their text."""
        def plain(value: Any) -> Any:
            if isinstance(value, Message):
                return value.to_dict()
            return value if isinstance(value, (str, int, float, bool, type(None))) else str(value)
        return {"template": self.template,
                "values": {key: plain(value) for key, value in self.values.items()}}

    @classmethod
    def from_dict(cls, data: Dict[str, Any]) -> Message:
        """The message of :meth:`to_dict`."""
        values = {key: cls.from_dict(value) if isinstance(value, dict) else value
                  for key, value in dict(data.get("values") or {}).items()}
        return cls(str(data.get("template", "")), values)


def fill(template: str, values: Dict[str, Any]) -> str:
    """``template`` with ``values`` filled in; a template without values as it is."""
    return template.format(**values) if values else template


def msg(template: str, **values: Any) -> Message:
    """A translatable phrase: the English ``template`` and its ``values``.

    Errors in ``values`` become their own :class:`Message` (when they have one) or their text,
    so a message never holds an exception (nor the frames of its traceback).
    """
    return Message(template, {key: _plain(value) for key, value in values.items()})


def _plain(value: Any) -> Any:
    if isinstance(value, PhotodemError):
        return value.message if value.message is not None else str(value)
    if isinstance(value, BaseException):
        return str(value)
    return value


class PhotodemError(Exception):
    """An error the operator can fix; the message is shown as it is.

    ``counts``: the figures behind the message as data (e.g. a failed georeferencing's pair
    and score counts); empty where there are none. ``message``: the template and values of a
    translatable error (:meth:`of`), else ``None``.
    """

    def __init__(self, message: str = "", counts: Optional[Dict[str, Any]] = None) -> None:
        super().__init__(message)
        self.counts: Dict[str, Any] = dict(counts or {})
        self.message: Optional[Message] = None

    @classmethod
    def of(cls, template: str, **values: Any) -> PhotodemError:
        """An error whose text the GUIs translate: ``str()`` gives ``template.format(**values)``.

        Examples
        --------
        >>> str(InputError.of("Parameter '{name}': '{path}' does not exist.",
        ...                   name="dsm", path="/x.tif"))
        "Parameter 'dsm': '/x.tif' does not exist."
        """
        message = msg(template, **values)
        error = cls(str(message))
        error.message = message
        return error


class InputError(PhotodemError):
    """An input file, layer or parameter is missing or unusable."""


class GeometryError(PhotodemError):
    """The photogrammetric geometry does not allow the operation (no overlap, ray misses DEM…)."""


class Cancelled(PhotodemError):
    """The operator cancelled the run; no output was left behind."""

    def __init__(self, message: str = "Cancelled by the operator; no output was written.") -> None:
        super().__init__(message)
