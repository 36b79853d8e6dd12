"""The motion model: where the next frame's search is centred. Without one, the search is centred
on the last box (the paper)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .frames import IntBox
from .geometry import centred
from .settings import MAX_SEARCH_RADIUS, check_choices, check_numbers, need

__all__ = ["MotionSettings", "VelocityMotion"]


@dataclass(frozen=True)
class MotionSettings:
    """The motion model (:mod:`wmiltrack.engine.motion`): where the search is centred.

    Attributes
    ----------
    motion : {"none", "velocity"}
        Centre the search on the last box (``none``: no motion model) or on a
        constant-velocity prediction of the box centre (``velocity``; falls back to the last
        box when the last frame's confidence was below ``lost_threshold``).
    motion_smoothing : float
        Weight of the old velocity in the exponential velocity estimate, in [0, 1).
    motion_max : float
        The predicted displacement is clipped to this many pixels per frame.
    """

    motion: Literal["none", "velocity"] = "none"
    motion_smoothing: float = 0.5
    motion_max: float = 30.0

    def __post_init__(self) -> None:
        MotionSettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_choices(self, {"motion": ("none", "velocity")})
        check_numbers(self, "motion_smoothing", "motion_max")
        need(0.0 <= self.motion_smoothing < 1.0,
             f"motion_smoothing must be in [0, 1), got {self.motion_smoothing}")
        need(0.0 <= self.motion_max <= MAX_SEARCH_RADIUS,
             f"motion_max must be in [0, {MAX_SEARCH_RADIUS}], got {self.motion_max}")


class VelocityMotion:
    """A constant-velocity prediction of the box centre, smoothed exponentially and clipped to
    ``motion_max`` pixels a frame; it resets to standing still whenever a frame is not
    confidently tracked (a lost target's last moves say nothing about where it is)."""

    def __init__(self, settings: MotionSettings) -> None:
        self.settings = settings
        self.velocity = (0.0, 0.0)
        self._lost = False

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """(The target stands still until it is seen to move.)"""
        self.velocity = (0.0, 0.0)
        self._lost = False

    def origin(self, box: IntBox, frame: np.ndarray | None = None) -> IntBox:
        """Where to centre the search for a target last seen at ``box`` (the frame is not
        needed: the prediction is from the past frames)."""
        if self._lost:
            return box
        vx, vy = self.velocity
        return centred(box, box[2], box[3], vx, vy)

    def follow(self, previous: IntBox, box: IntBox, tracked: bool) -> None:
        """Learn from a frame that moved the target from ``previous`` to ``box``."""
        s = self.settings
        self._lost = not tracked
        if not tracked:
            self.velocity = (0.0, 0.0)
            return
        mx = box[0] + box[2] / 2.0 - (previous[0] + previous[2] / 2.0)
        my = box[1] + box[3] / 2.0 - (previous[1] + previous[3] / 2.0)
        a = s.motion_smoothing
        vx = a * self.velocity[0] + (1.0 - a) * mx
        vy = a * self.velocity[1] + (1.0 - a) * my
        speed = math.hypot(vx, vy)
        if speed > s.motion_max:
            vx, vy = vx * s.motion_max / speed, vy * s.motion_max / speed
        self.velocity = (vx, vy)
