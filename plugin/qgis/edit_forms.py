"""The editing forms of the QGIS toolbar: the shared Qt-only forms of
:mod:`photodem.plugin.widgets.edit_forms` (one copy for QGIS and the standalone map)."""

from __future__ import annotations

from ..widgets.edit_forms import (  # noqa: F401 (re-exported for the QGIS tools and tests)
    HEIGHT_RANGE,
    ActionDialog,
    BreaklineDialog,
    DialogAsker,
    HeightDialog,
    action_labels,
    box_value,
    height_box,
    kind_labels,
)
