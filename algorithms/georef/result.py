"""The result of a georeferencing (:func:`.pipeline.georeference`), before anything is written.

Its own module: the writers (:mod:`.products`) and the review (:mod:`.review`) use it without
the matching chain.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

import numpy as np

from .fit import TransformFit
from .refinement import ControlPoint


@dataclass
class GeorefResult:
    """The result of :func:`georeference` (nothing written yet; see :mod:`.products`).

    Only the first four fields are needed to write the transform products (the review
    builds such a result from its edited control points).
    """

    fit: TransformFit  #: the final image → map transform
    inverse_fit: TransformFit  #: map → image, for resampling
    gcps: List[ControlPoint]  #: the control points (``fit.used`` marks the ones used)
    crs: Any  #: CRS of the map coordinates (pyproj)
    global_transform: Optional[np.ndarray] = None  #: 3 × 3 after the verification
    joint: Optional[np.ndarray] = None  #: 3 × 3 after the joint ICP
    search: Optional[np.ndarray] = None  #: 3 × 3 of the consistency search
    pairs: List[Any] = field(default_factory=list)  #: verified object pairs
    img_features: List[Any] = field(default_factory=list)
    ref_features: List[Any] = field(default_factory=list)
    counts: Dict[str, Any] = field(default_factory=dict)  #: figures of every stage
    icp: List[Dict[str, Any]] = field(default_factory=list)  #: per-pair ICP figures
    segmentation: Dict[str, Any] = field(default_factory=dict)
    reference: Dict[str, Any] = field(default_factory=dict)  #: about the reference layer
    reference_kind: str = "vector"  #: "vector" or "raster"
    image_info: Dict[str, Any] = field(default_factory=dict)
    grey: Optional[np.ndarray] = None  #: the grey image matched (level 0)
    warnings: List[str] = field(default_factory=list)
    seconds: float = 0.0
    stage: str = "objects"  #: "objects" or "area"
    parameters: Dict[str, Any] = field(default_factory=dict)  #: see GeorefOptions.report
    area: Optional[Dict[str, Any]] = None  #: the area-based search, when it gave the result
    reference_rings: List[Any] = field(default_factory=list)  #: drawn in the overlay (area)
    #: independent evidence (:class:`.evidence.Evidence`; ``None``: not assessed)
    evidence: Optional[Any] = None
    #: the acceptance gate's verdict (``None``: not assessed; False: written as unverified)
    verified: Optional[bool] = None
