"""OpenCV-shaped trackers (``TrackerRCWMIL.create()``, ``init``, ``update -> (ok, rect)``).

The stable public path of :mod:`wmiltrack.integrations.opencv`, where they are defined.
"""

from .integrations.opencv import (
    TrackerCompat,
    TrackerCT,
    TrackerFCT,
    TrackerMILBoost,
    TrackerOSIL,
    TrackerRCWMIL,
    TrackerRCWMILPlus,
    TrackerWMIL,
)

__all__ = ["TrackerCT", "TrackerCompat", "TrackerFCT", "TrackerMILBoost", "TrackerOSIL",
           "TrackerRCWMIL", "TrackerRCWMILPlus", "TrackerWMIL"]
