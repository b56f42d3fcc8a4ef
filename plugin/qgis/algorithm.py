"""One generic QgsProcessingAlgorithm for every PhotoDEM algorithm spec.

:class:`PhotodemAlgorithm` is built from an :class:`~photodem.algorithms.processing.spec.Algorithm`
(the one declaration): each spec parameter becomes the matching ``QgsProcessingParameter*``, each
spec output a ``QgsProcessingOutput*``. ``processAlgorithm`` turns the QGIS values back into the
raw dict the CLI would pass and calls :func:`~photodem.algorithms.processing.registry.run`, so a
run inside QGIS gives exactly the result of a run from Python or the CLI.

QGIS-specific value rules (for ``processing.run`` and ``qgis_process``):

* ``enum``: QGIS passes the option *index*; it is turned back into the option string.
* ``extent``: QGIS writes ``xmin,xmax,ymin,ymax [CRS]``; the core wants
  ``(xmin, ymin, xmax, ymax)``.
* ``crs``: passed on as its ``authid`` (``EPSG:25832``), or WKT when it has none.
* layers: passed on as the path of their source.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Dict, List, Optional

from qgis.core import (
    QgsCoordinateReferenceSystem,
    QgsProcessing,
    QgsProcessingAlgorithm,
    QgsProcessingContext,
    QgsProcessingException,
    QgsProcessingFeedback,
    QgsProcessingLayerPostProcessorInterface,
    QgsProcessingOutputFile,
    QgsProcessingOutputFolder,
    QgsProcessingOutputHtml,
    QgsProcessingOutputNumber,
    QgsProcessingOutputRasterLayer,
    QgsProcessingOutputString,
    QgsProcessingOutputVectorLayer,
    QgsProcessingParameterBoolean,
    QgsProcessingParameterCrs,
    QgsProcessingParameterDefinition,
    QgsProcessingParameterEnum,
    QgsProcessingParameterExtent,
    QgsProcessingParameterFile,
    QgsProcessingParameterFileDestination,
    QgsProcessingParameterFolderDestination,
    QgsProcessingParameterMultipleLayers,
    QgsProcessingParameterNumber,
    QgsProcessingParameterRasterDestination,
    QgsProcessingParameterRasterLayer,
    QgsProcessingParameterString,
    QgsProcessingParameterVectorDestination,
    QgsProcessingParameterVectorLayer,
)

from ...algorithms.errors import PhotodemError
from ...algorithms.feedback import Feedback
from ...algorithms.processing import registry
from ...algorithms.processing.spec import Algorithm, Output, Parameter
from ...algorithms.project.products import Product, classify
from ..i18n import error_text, tr
from ..qt import QIcon
from .workspace import layer_uri, place_output_layer, product_label

#: The widget wrapper of ``model`` parameters, by its dotted path (see ``model_widget``).
MODEL_WIDGET_WRAPPER = f"{__package__}.model_widget.ModelWidgetWrapper"


class QgisFeedback(Feedback):
    """PhotoDEM :class:`Feedback` on top of a ``QgsProcessingFeedback``.

    Progress goes to ``setProgress``, cancellation comes from ``isCanceled`` (the Cancel button of
    the Processing dialog, Ctrl+C in ``qgis_process``), log lines go to ``pushInfo`` and warnings
    to ``pushWarning``. Lines and warnings are also recorded like the base class does.
    """

    def __init__(self, feedback: Optional[QgsProcessingFeedback]) -> None:
        super().__init__()
        self.qgis_feedback = feedback

    def cancel(self) -> None:
        super().cancel()
        if self.qgis_feedback is not None:
            self.qgis_feedback.cancel()

    def is_canceled(self) -> bool:
        if super().is_canceled():
            return True
        return bool(self.qgis_feedback is not None and self.qgis_feedback.isCanceled())

    def progress(self, percent: float) -> None:
        self.percent = float(min(max(percent, 0.0), 100.0))
        if self.qgis_feedback is not None:
            self.qgis_feedback.setProgress(self.percent)
        self.check()

    def info(self, message: str) -> None:
        super().info(message)
        if self.qgis_feedback is not None:
            self.qgis_feedback.pushInfo(message)

    def warning(self, message: str) -> None:
        super().warning(message)
        if self.qgis_feedback is not None:
            if hasattr(self.qgis_feedback, "pushWarning"):  # QGIS ≥ 3.16
                self.qgis_feedback.pushWarning(message)
            else:  # pragma: no cover
                self.qgis_feedback.reportError(message, False)


# -- parameters ---------------------------------------------------------------------------------
def _file_filter(p: Parameter) -> str:
    """A Qt file-dialog filter from the spec's extensions (empty: any file)."""
    if not p.extensions:
        return ""
    patterns = " ".join("*" + (e if e.startswith(".") else "." + e) for e in p.extensions)
    return f"{tr(p.description)} ({patterns})"


def _extent_to_qgis(value: Any) -> Optional[str]:
    """Spec extent ``(xmin, ymin, xmax, ymax)`` → QGIS string ``xmin,xmax,ymin,ymax``."""
    if value is None:
        return None
    if isinstance(value, str):
        value = [v for v in value.replace(";", ",").split(",") if v.strip()]
    xmin, ymin, xmax, ymax = (float(v) for v in value)
    return f"{xmin!r},{xmax!r},{ymin!r},{ymax!r}"


def make_parameter(p: Parameter) -> QgsProcessingParameterDefinition:
    """The QGIS parameter definition for a spec parameter."""
    name, desc, kind, optional = p.name, tr(p.description), p.kind, p.optional
    default = p.default
    if kind == "raster":
        q = QgsProcessingParameterRasterLayer(name, desc, defaultValue=default, optional=optional)
    elif kind == "vector":
        q = QgsProcessingParameterVectorLayer(
            name, desc, [QgsProcessing.TypeVectorAnyGeometry], defaultValue=default,
            optional=optional,
        )
    elif kind == "file":
        q = QgsProcessingParameterFile(
            name, desc, behavior=QgsProcessingParameterFile.File, defaultValue=default,
            optional=optional, fileFilter=_file_filter(p),
        )
    elif kind in ("folder", "project"):  # the two input folders
        q = QgsProcessingParameterFile(
            name, desc, behavior=QgsProcessingParameterFile.Folder, defaultValue=default,
            optional=optional,
        )
    elif kind == "output_folder":
        q = QgsProcessingParameterFolderDestination(
            name, desc, defaultValue=default, optional=optional
        )
    elif kind == "output_file":
        q = QgsProcessingParameterFileDestination(
            name, desc, fileFilter=_file_filter(p), defaultValue=default, optional=optional
        )
    elif kind == "output_raster":
        q = QgsProcessingParameterRasterDestination(
            name, desc, defaultValue=default, optional=optional
        )
    elif kind == "output_vector":
        q = QgsProcessingParameterVectorDestination(
            name, desc, defaultValue=default, optional=optional
        )
    elif p.is_numeric:
        number_type = (
            QgsProcessingParameterNumber.Integer if p.is_integer
            else QgsProcessingParameterNumber.Double
        )
        q = QgsProcessingParameterNumber(
            name, desc, type=number_type, defaultValue=default, optional=optional
        )
        if p.minimum is not None:
            q.setMinimum(p.minimum)
        if p.maximum is not None:
            q.setMaximum(p.maximum)
        if not p.is_integer:  # QGIS shows 6 decimals otherwise ("25.000000")
            q.setMetadata({"widget_wrapper": {"decimals": 3}})
    elif p.is_choice:
        index = None
        if default is not None:
            index = _option_index(p, default)
        q = QgsProcessingParameterEnum(
            name, desc, options=[tr(o) for o in p.options], allowMultiple=False,
            defaultValue=index, optional=optional,
        )
    elif p.is_bool:
        q = QgsProcessingParameterBoolean(
            name, desc, defaultValue=None if default is None else bool(default), optional=optional
        )
    elif kind == "crs":
        q = QgsProcessingParameterCrs(name, desc, defaultValue=default, optional=optional)
    elif kind == "extent":
        q = QgsProcessingParameterExtent(
            name, desc, defaultValue=_extent_to_qgis(default), optional=optional
        )
    elif p.is_item_name or kind == "string":
        q = QgsProcessingParameterString(
            name, desc, defaultValue=None if default is None else str(default),
            optional=optional,
        )
        if kind == "model":  # a drop-down of the project's models (a class path: imported
            # only when a dialog is built, never under qgis_process)
            q.setMetadata({"widget_wrapper": {"class": MODEL_WIDGET_WRAPPER}})
    elif p.is_list:
        q = QgsProcessingParameterMultipleLayers(
            name, desc, QgsProcessing.TypeRaster, defaultValue=default, optional=optional
        )
    else:  # pragma: no cover - spec.Parameter rejects unknown kinds
        raise ValueError(f"no QGIS parameter for kind {kind!r}")
    help_text = p.help or p.description
    if help_text and hasattr(q, "setHelp"):
        q.setHelp(tr(help_text))
    return q


def _option_index(p: Parameter, value: Any) -> int:
    """Index of an enum option given as string (case-insensitive) or index."""
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    lowered = [o.lower() for o in p.options]
    return lowered.index(str(value).strip().lower())


def make_output(o: Output):
    """The QGIS output definition for a spec output (``json`` becomes a string output,
    ``html`` an HTML output that the Results Viewer lists)."""
    cls = {
        "folder": QgsProcessingOutputFolder,
        "file": QgsProcessingOutputFile,
        "html": QgsProcessingOutputHtml,  # shown in the Results Viewer
        "raster": QgsProcessingOutputRasterLayer,
        "vector": QgsProcessingOutputVectorLayer,
        "number": QgsProcessingOutputNumber,
        "string": QgsProcessingOutputString,
        "json": QgsProcessingOutputString,
    }[o.kind]
    return cls(o.name, tr(o.description))


def _missing(value: Any) -> bool:
    """True for "no value": absent, None, a NULL QVariant or an empty string."""
    if value is None:
        return True
    if isinstance(value, str) and value.strip() == "":
        return True
    is_null = getattr(value, "isNull", None)  # QVariant NULL from a model or the dialog
    if callable(is_null) and type(value).__name__ == "QVariant":
        return bool(is_null())
    return False


def _is_temporary(value: Any) -> bool:
    """True for QGIS's "temporary output" (a text or an output definition's sink)."""
    sink = getattr(value, "sink", None)
    if sink is not None:
        value = sink.staticValue()
    return isinstance(value, str) and value == QgsProcessing.TEMPORARY_OUTPUT


def _layer_path(layer: Any) -> Optional[str]:
    """File path of a layer's source (OGR's ``|layername=…`` suffix removed)."""
    if layer is None:
        return None
    return layer.source().split("|")[0]


# -- the algorithm ------------------------------------------------------------------------------
class PhotodemAlgorithm(QgsProcessingAlgorithm):
    """The QGIS face of one PhotoDEM algorithm spec.

    Parameters
    ----------
    spec : Algorithm
        The declaration from :func:`photodem.algorithms.processing.registry.algorithms`.
    icon : QIcon, optional
        Icon shown in the toolbox (the provider's).
    """

    def __init__(self, spec: Algorithm, icon: Optional[QIcon] = None) -> None:
        super().__init__()
        self.spec = spec
        self._icon = icon

    # -- identity ---------------------------------------------------------------------------
    def createInstance(self) -> PhotodemAlgorithm:
        return PhotodemAlgorithm(self.spec, self._icon)

    def name(self) -> str:
        return self.spec.id

    def displayName(self) -> str:
        return tr(self.spec.name or self.spec.id)

    def group(self) -> str:
        return tr(self.spec.group)

    def groupId(self) -> str:
        if self.spec.group_id:
            return self.spec.group_id
        return re.sub(r"[^a-z0-9]+", "_", self.spec.group.lower()).strip("_")

    def shortHelpString(self) -> str:
        parts: List[str] = []
        if self.spec.help:
            parts.append(tr(self.spec.help))
        rows = [
            f"<b>{tr(p.description)}</b> ({p.name}): {tr(p.help)}"
            for p in self.spec.parameters
            if p.help
        ]
        if rows:
            parts.append("<br>".join(rows))
        return "<p>" + "</p><p>".join(parts) + "</p>" if parts else ""

    def icon(self) -> QIcon:
        return self._icon if self._icon is not None else super().icon()

    def tags(self) -> List[str]:
        return ["photodem", "photogrammetry", self.spec.id]

    # -- definition -------------------------------------------------------------------------
    def initAlgorithm(self, config: Optional[Dict[str, Any]] = None) -> None:
        for p in self.spec.parameters:
            self.addParameter(make_parameter(p))
        destinations = {p.name for p in self.spec.parameters if p.is_output}
        for o in self.spec.outputs:
            if o.name not in destinations:  # a destination parameter already adds its output
                self.addOutput(make_output(o))

    # -- run ---------------------------------------------------------------------------------
    def raw_parameters(self, parameters: Dict[str, Any], context) -> Dict[str, Any]:
        """Convert QGIS parameter values into the raw dict that ``registry.run`` takes.

        Missing values stay missing, so the spec's own defaults apply exactly as in the CLI. An
        optional output left empty in the Processing dialog arrives as "temporary output"; it
        counts as missing too, so e.g. a DSM goes to ``products/dsm/<model>/`` as its help says,
        not into a temporary folder that is gone with the session.
        """
        raw: Dict[str, Any] = {}
        for p in self.spec.parameters:
            value = parameters.get(p.name)
            if _missing(value) or (p.is_output and p.optional and _is_temporary(value)):
                continue
            raw[p.name] = self._convert(p, value, parameters, context)
        return {k: v for k, v in raw.items() if v is not None}

    def _convert(self, p: Parameter, value: Any, parameters: Dict[str, Any], context) -> Any:
        name, kind = p.name, p.kind
        if kind == "raster":
            if isinstance(value, str) and _is_file(value):
                return value
            return _layer_path(self.parameterAsRasterLayer(parameters, name, context))
        if kind == "vector":
            if isinstance(value, str) and _is_file(value.split("|")[0]):
                return value.split("|")[0]
            return _layer_path(self.parameterAsVectorLayer(parameters, name, context))
        if kind == "file" or (p.is_folder and not p.is_output):
            return self.parameterAsFile(parameters, name, context) or None
        if kind in ("output_folder", "output_file"):
            return self.parameterAsFileOutput(parameters, name, context) or None
        if p.is_output:  # a raster or vector layer destination
            return self.parameterAsOutputLayer(parameters, name, context) or None
        if p.is_integer:
            return self.parameterAsInt(parameters, name, context)
        if p.is_numeric:
            return self.parameterAsDouble(parameters, name, context)
        if p.is_choice:
            if isinstance(value, str) and not value.strip().lstrip("-").isdigit():
                return value  # an option name (a batch file); the spec checks it
            return p.options[self.parameterAsEnum(parameters, name, context)]
        if p.is_bool:
            return self.parameterAsBoolean(parameters, name, context)
        if kind == "crs":
            crs = self.parameterAsCrs(parameters, name, context)
            if not crs.isValid():
                return None
            return crs.authid() or crs.toWkt(QgsCoordinateReferenceSystem.WKT_PREFERRED)
        if kind == "extent":
            rect = self.parameterAsExtent(parameters, name, context)
            if rect.isNull():
                return None
            return (rect.xMinimum(), rect.yMinimum(), rect.xMaximum(), rect.yMaximum())
        if p.is_list:
            if isinstance(value, (list, tuple)) and all(
                isinstance(v, str) and _is_file(v) for v in value
            ):
                return list(value)
            layers = self.parameterAsLayerList(parameters, name, context)
            return [_layer_path(layer) for layer in layers]
        return self.parameterAsString(parameters, name, context)  # model, image, string

    def processAlgorithm(self, parameters: Dict[str, Any], context, feedback) -> Dict[str, Any]:
        raw = self.raw_parameters(parameters, context)
        adapter = QgisFeedback(feedback)
        try:
            result = registry.run(self.spec.id, raw, adapter)
        except PhotodemError as exc:  # operator errors: message only, no traceback
            raise QgsProcessingException(error_text(exc)) from exc
        load_on_completion(self.spec, result, context)
        return result


# -- outputs on the map -------------------------------------------------------------------------
#: Post-processors of layers still to be loaded: QGIS keeps no reference of its own, so without
#: this list Python would delete them before the layers are loaded.
_PENDING: List[QgsProcessingLayerPostProcessorInterface] = []
_PENDING_MAX = 256


class ProductPostProcessor(QgsProcessingLayerPostProcessorInterface):
    """Styles a layer loaded at the end of a run and puts it into the open workspace's
    Products group when the file lies under that project (see :func:`.workspace
    .place_output_layer`)."""

    def __init__(self, kind: Optional[str]) -> None:
        super().__init__()
        self.kind = kind
        _PENDING.append(self)
        del _PENDING[:-_PENDING_MAX]  # runs whose layers were never loaded (processing.run)

    def postProcessLayer(self, layer, context, feedback) -> None:  # noqa: N802
        try:
            place_output_layer(layer, self.kind)
        finally:
            if self in _PENDING:
                _PENDING.remove(self)


def main_outputs(spec: Algorithm, result: Dict[str, Any]) -> List[tuple]:
    """``(output, path, product)`` of the main raster/vector files of a run: every file that is a
    known product (DSM, DTM, ortho…), else the first raster/vector file."""
    files = []
    for o in spec.outputs:
        value = result.get(o.name)
        if o.kind in ("raster", "vector") and isinstance(value, str) and _is_file(value):
            files.append((o, value, classify(value)))
    products = [f for f in files if f[2] is not None]
    return products or files[:1]


def load_on_completion(spec: Algorithm, result: Dict[str, Any], context) -> None:
    """Register the main outputs of a run to be loaded when it ends (the toolbox dialog,
    ``processing.runAndLoadResults``), styled by :class:`ProductPostProcessor`. A file that
    QGIS already loads (a destination parameter) keeps its entry and gets the post-processor."""
    project = context.project() if context is not None else None
    if project is None:
        return
    known = {_resolved(key): key for key in context.layersToLoadOnCompletion()}
    for output, path, product in main_outputs(spec, result):
        key = known.get(_resolved(path), layer_uri(product) if product is not None else path)
        name = product_label(product, tr(output.description))
        details = QgsProcessingContext.LayerDetails(name, project, output.name)
        details.setPostProcessor(ProductPostProcessor(_kind(product)))
        context.addLayerToLoadOnCompletion(key, details)


def _kind(product: Optional[Product]) -> Optional[str]:
    return product.kind if product is not None else None


def _resolved(path: str) -> str:
    try:
        return str(Path(path).resolve())
    except (OSError, ValueError):
        return path


def _is_file(path: str) -> bool:
    try:
        return Path(path).exists()
    except OSError:
        return False
