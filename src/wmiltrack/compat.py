"""OpenCV-shaped trackers (``TrackerRCWMIL.create()``, ``init``, ``update -> (ok, rect)``).

The stable public path of :mod:`wmiltrack.integrations.opencv_shaped`, where they are defined.
"""

from .integrations.opencv_shaped import (
    COMPAT_CLASSES,
    TrackerCompat,
    TrackerCT,
    TrackerFCT,
    TrackerMILBoost,
    TrackerOSIL,
    TrackerRCWMIL,
    TrackerRCWMILCF,
    TrackerRCWMILNano,
    TrackerRCWMILPlus,
    TrackerWMIL,
)

__all__ = ["COMPAT_CLASSES", "TrackerCT", "TrackerCompat", "TrackerFCT", "TrackerMILBoost",
           "TrackerOSIL", "TrackerRCWMIL", "TrackerRCWMILCF", "TrackerRCWMILNano", "TrackerRCWMILPlus",
           "TrackerWMIL"]
