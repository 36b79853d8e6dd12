"""Re-detection: a part that keeps a grey picture of the target and looks for it over the whole
frame while the target is lost.

The classifier and the cues learn from whatever the box covers; when an occluder covers the
target or the target leaves the view, they learn the occluder or the background within a few
frames and the reported score climbs back, so the tracker never says it lost anything and
never looks further than its local search. The judge (:mod:`.judge`) notices a hidden or
departed target and holds it for lost (nothing learns then); one of the witnesses it asks is
the box's correlation with this part's grey picture of the target (:meth:`Redetector.likeness`).
While the target is lost every frame is searched whole for its last confident look.

That search does not use the classifier: Haar sums on raw intensities, frozen while the target
is away, stop recognising it as soon as the lighting changes (on the generated sequences its
confidence on the returned target falls from 0.6 to below 0.1 within twenty frames). A
normalised cross-correlation with a grey picture of the target (OpenCV's ``matchTemplate``,
which runs over a whole frame in a few milliseconds) is indifferent to gain and offset: 0.86 to
0.97 on the returned target there, 0.47 to 0.77 at the best other place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from .frames import IntBox
from .settings import check_numbers, need

__all__ = ["Redetector", "RecoverySettings", "check_recover_memory"]


def check_recover_memory(obj: Any) -> None:
    """``recover_memory``, which the judge's and the recovery's settings share, checked."""
    check_numbers(obj, "recover_memory")
    need(0.0 <= obj.recover_memory < 1.0,
         f"recover_memory must be in [0, 1), got {obj.recover_memory}")


@dataclass(frozen=True)
class RecoverySettings:
    """The re-detection of a lost target (:class:`wmiltrack.engine.recovery.Redetector`; the
    judge's ``redetect``, ``lost_drop`` and ``recover_warmup`` start the lost state).

    A target that is hidden (a full occlusion) or gone (out of view) must not be learnt: the
    classifier, the cues and the scale model would adopt the occluder or the background, and the
    score would climb back as if the target were there. With ``redetect``, a frame whose
    classifier confidence drops below ``lost_drop`` times its running mean over tracked frames
    starts the lost state: the box is held at the last confident one, ``ok`` is False and
    nothing learns. Each lost frame searches the whole frame for the target's grey template
    (kept from the tracked frames) by normalised cross-correlation, and takes the best place
    back once its correlation reaches both ``recover_floor`` and ``recover_ratio`` times the
    tracked boxes' running correlation (the latter lowered by ``recover_decay`` per lost
    frame); a fine search there gives the box. A lost frame whose usual search around the
    held box finds the classifier's confidence back above ``lost_drop`` times its running mean
    ends the lost state there.

    Attributes
    ----------
    recover_ratio : float
        A re-detected place is taken when its correlation with the template is at least this
        fraction of the tracked boxes' running correlation.
    recover_decay : float
        ``recover_ratio`` is multiplied by this for every frame lost so far (1: never lowered).
    recover_floor : float
        The least correlation a re-detected place needs in any case: people, cars and textures
        of one kind reach 0.7-0.77 at the wrong place on the shared sequences.
    recover_memory : float
        Weight of the old value in the running mean of the tracked boxes' correlation with the
        template, in [0, 1) (the judge's running means take the same weight:
        :class:`~wmiltrack.engine.judge.JudgeSettings`).
    recover_template_rate : float
        Weight of each tracked frame's patch in the grey template, in (0, 1].
    recover_template_area : float
        The template holds at most this many pixels (the box's aspect): a larger target is
        matched on frames shrunk by the same factor, and the fine search after a re-detection
        places the box to the pixel. Keeps a large target's per-frame cost and whole-frame
        search small.
    recover_search_area : float
        The whole-frame pass of the re-detection matches a template of at most this many
        pixels (the frame shrunk alike); the place it finds is checked at the template's
        resolution.
    """

    recover_ratio: float = 0.9
    recover_decay: float = 1.0
    recover_floor: float = 0.9
    recover_memory: float = 0.9
    recover_template_rate: float = 0.05
    recover_template_area: float = 1600.0
    recover_search_area: float = 256.0

    def __post_init__(self) -> None:
        RecoverySettings.check(self)

    def check(self) -> None:
        """``ValueError`` naming the first setting out of range."""
        check_numbers(self, "recover_ratio", "recover_decay", "recover_floor")
        need(0.0 < self.recover_ratio <= 1.0,
             f"recover_ratio must be in (0, 1], got {self.recover_ratio}")
        need(0.0 < self.recover_decay <= 1.0,
             f"recover_decay must be in (0, 1], got {self.recover_decay}")
        need(-1.0 <= self.recover_floor <= 1.0,
             f"recover_floor must be in [-1, 1], got {self.recover_floor}")
        check_numbers(self, "recover_memory", "recover_template_rate", "recover_template_area",
                      "recover_search_area")
        check_recover_memory(self)
        need(0.0 < self.recover_template_rate <= 1.0,
             f"recover_template_rate must be in (0, 1], got {self.recover_template_rate}")
        need(self.recover_template_area >= 1.0 and self.recover_search_area >= 1.0,
             "recover_template_area and recover_search_area must be >= 1")


def _grey(frame: np.ndarray) -> np.ndarray:
    if frame.ndim == 2:
        return frame
    if frame.shape[2] == 1:
        return frame[:, :, 0]
    return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)


def _match(a: np.ndarray, b: np.ndarray) -> float:
    """Normalised cross-correlation of two patches of one size (0 when one is flat), from
    sums in double: a quarter of OpenCV's time for one pair (element-wise products, not
    ``@``, which would wake a threaded BLAS for every frame)."""
    x, y = a.ravel().astype(np.float64), b.ravel().astype(np.float64)
    n = x.size
    sx, sy = float(x.sum()), float(y.sum())
    sxy = float((x * y).sum()) - sx * sy / n
    sxx, syy = float((x * x).sum()) - sx * sx / n, float((y * y).sum()) - sy * sy / n
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else 0.0


class Redetector:
    """The re-detection of one tracker (``Params.redetect``; see
    :class:`RecoverySettings`).

    ``picture`` is the grey picture of the target, ``match`` the running mean of the tracked
    boxes' correlation with it (both frozen while the target is lost: nothing learns then).
    ``last`` is the last re-detection's best correlation; ``size`` the size of the last tracked
    box that matched the picture at least as well as usual (what :meth:`find` looks for).
    """

    def __init__(self, settings: RecoverySettings) -> None:
        self.settings = settings
        self.match: float | None = None
        self.last = math.nan
        self.picture: np.ndarray | None = None
        self.size: tuple[int, int] | None = None  # of the last box that matched as usual

    def start(self, frame: np.ndarray, box: IntBox) -> None:
        """Take the first look of the target as the picture; no history."""
        self.match = None
        self.last = math.nan
        self.picture = None
        self.size = (box[2], box[3])
        self.learn(frame, box)

    def _patch(self, frame: np.ndarray, box: IntBox) -> np.ndarray | None:
        """The box's grey pixels at the picture's size (at most ``recover_template_area`` pixels;
        None if the box leaves the frame)."""
        x, y, w, h = box
        fh, fw = frame.shape[:2]
        if x < 0 or y < 0 or x + w > fw or y + h > fh or w < 1 or h < 1:
            return None
        patch = _grey(frame[y:y + h, x:x + w]).astype(np.float32)
        if self.picture is not None:
            size = self.picture.shape[::-1]
        else:
            shrink = min(1.0, math.sqrt(self.settings.recover_template_area / (w * h)))
            size = (max(1, round(w * shrink)), max(1, round(h * shrink)))
        if patch.shape[::-1] != size:
            patch = np.asarray(cv2.resize(patch, size, interpolation=cv2.INTER_AREA),
                               dtype=np.float32)
        return patch

    def learn(self, frame: np.ndarray, box: IntBox) -> None:
        """Fold a tracked frame's box into the picture and the running match."""
        patch = self._patch(frame, box)
        if patch is None:
            return
        if self.picture is None:
            self.picture = patch
            return
        m = _match(patch, self.picture)
        if self.match is None or m >= self.match:
            self.size = (box[2], box[3])
        a, rate = self.settings.recover_memory, self.settings.recover_template_rate
        self.match = m if self.match is None else a * self.match + (1.0 - a) * m
        cv2.addWeighted(self.picture, 1.0 - rate, patch, rate, 0.0, dst=self.picture)

    def likeness(self, frame: np.ndarray, box: IntBox) -> tuple[float, float] | None:
        """The correlation of ``box``'s grey pixels with the picture and the tracked boxes'
        running mean of it (what the judge compares), or None without a picture or a mean,
        or when the box leaves the frame."""
        patch = self._patch(frame, box)
        if patch is None or self.picture is None or self.match is None:
            return None
        return _match(patch, self.picture), self.match

    def required(self, frames_lost: int) -> float:
        """The correlation with the picture a re-detected box needs to end the lost state
        after ``frames_lost`` frames in it."""
        s = self.settings
        match = self.match if self.match is not None else 1.0
        relative = s.recover_ratio * match * s.recover_decay ** max(frames_lost - 1, 0)
        return max(s.recover_floor, relative)

    def find(self, frame: np.ndarray, frames_lost: int) -> IntBox | None:
        """The box that matches the picture best over the whole frame (:meth:`best_place`),
        if it matches well enough (:meth:`required`) to end a lost state of ``frames_lost``
        frames so far; else None."""
        place = self.best_place(frame)
        if place is None:
            return None
        best, box = place
        self.last = best
        if not best >= self.required(frames_lost):
            return None
        return box

    def best_place(self, frame: np.ndarray) -> tuple[float, IntBox] | None:
        """The box of the whole frame that matches the picture best, and its correlation
        (None without a picture, or when the box would not fit the frame); changes nothing.
        The box has the size of the last tracked box that matched the picture at least as
        well as usual (:attr:`size`): a target that an occluder covered bit by bit may have
        had its box shrunk or grown before it counted as lost.

        Two passes: the whole frame at a resolution where the picture has at most
        ``recover_search_area`` pixels (a 32-px target on a 640 x 480 frame: 0.6 instead of 4 ms),
        then the neighbourhood of its best place at the picture's own resolution, whose
        correlation decides."""
        if self.picture is None or self.size is None:
            return None
        w, h = self.size
        fh, fw = frame.shape[:2]
        if w > fw or h > fh:
            return None
        best, (bx, by) = self._whole_frame(_grey(frame), w, h)
        return best, (bx, by, w, h)

    def similarity(self, frame: np.ndarray, box: IntBox) -> float:
        """The correlation of ``box``'s grey pixels with the picture (NaN without a picture
        or when the box leaves the frame): what :meth:`best_place` maximises."""
        patch = self._patch(frame, box)
        if patch is None or self.picture is None:
            return math.nan
        return _match(patch, self.picture)

    def _whole_frame(self, grey: np.ndarray, w: int, h: int) -> tuple[float, tuple[int, int]]:
        """The best correlation of the picture with a ``w x h`` box of the grey frame, and that
        box's top-left corner (see :meth:`find`)."""
        assert self.picture is not None
        fh, fw = grey.shape
        th, tw = self.picture.shape
        # Pass 2's scale: the picture's resolution, relative to the frame (a box of w x h
        # becomes the picture's size; a box smaller than the picture: the frame's own).
        sx, sy = min(1.0, tw / w), min(1.0, th / h)
        templ = self.picture
        if templ.shape != (round(h * sy), round(w * sx)):
            templ = cv2.resize(templ, (round(w * sx), round(h * sy)), interpolation=cv2.INTER_AREA)
        # Pass 1: the whole frame with the picture shrunk to at most recover_search_area pixels.
        c = min(1.0, math.sqrt(self.settings.recover_search_area / templ.size))
        small = cv2.resize(templ, (max(4, round(templ.shape[1] * c)), max(4, round(templ.shape[0] * c))),
                           interpolation=cv2.INTER_AREA) if c < 1.0 else templ
        cx, cy = sx * small.shape[1] / templ.shape[1], sy * small.shape[0] / templ.shape[0]
        shrunk = cv2.resize(grey, (max(small.shape[1], round(fw * cx)), max(small.shape[0], round(fh * cy))),
                            interpolation=cv2.INTER_AREA) if cx < 1.0 or cy < 1.0 else grey
        _, _, _, (x1, y1) = cv2.minMaxLoc(cv2.matchTemplate(shrunk.astype(np.float32), small,
                                                            cv2.TM_CCOEFF_NORMED))
        # Pass 2: around that place, a window two pass-1 pixels wider on every side.
        m = math.ceil(2.0 / min(cx, cy)) + 1
        x0 = min(max(round(x1 / cx) - m, 0), fw - w)
        y0 = min(max(round(y1 / cy) - m, 0), fh - h)
        x_end, y_end = min(fw, x0 + w + 2 * m), min(fh, y0 + h + 2 * m)
        window = grey[y0:y_end, x0:x_end]
        if sx < 1.0 or sy < 1.0:
            window = cv2.resize(window, (max(templ.shape[1], round(window.shape[1] * sx)),
                                         max(templ.shape[0], round(window.shape[0] * sy))),
                                interpolation=cv2.INTER_AREA)
        _, best, _, (x2, y2) = cv2.minMaxLoc(cv2.matchTemplate(window.astype(np.float32), templ,
                                                               cv2.TM_CCOEFF_NORMED))
        bx = min(max(x0 + round(x2 / sx), 0), fw - w)
        by = min(max(y0 + round(y2 / sy), 0), fh - h)
        return float(best), (int(bx), int(by))
