"""What a world declares about its outcome space, so that the learner's distances are relative.

Every distance the learner uses (when a goal counts as reached, how far mode 3 looks around a
goal, the narrowest region, the teacher's tolerance) depends on two quantities of the world:
its outcome box (where goals may be drawn) and its outcome noise (how far apart two executions
of the same action land). Absolute values tuned on one world are wrong by several times on
another, so ``LearnerConfig`` holds multiples of these two, and ``WorldScale`` turns them
into outcome units.

The noise is measured the paper's way: the mean Euclidean distance between the outcomes of
repeated executions of one action and their mean, averaged over actions (Nguyen et al. 2011
report 0.073 for their fishing rod). For Gaussian outcome noise of standard deviation sigma on
each of two axes that is sigma * sqrt(pi / 2) (``gaussian_noise_2d``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import portable


def gaussian_noise_2d(sigma: float) -> float:
    """The paper's noise measure for isotropic 2-D Gaussian noise: E|N(0, sigma^2 I)|."""
    return float(sigma * math.sqrt(math.pi / 2.0))


@dataclass(frozen=True)
class WorldScale:
    """The outcome box [low, high] and the outcome noise, in the world's outcome units."""

    low: tuple[float, ...]
    high: tuple[float, ...]
    noise: float

    def __post_init__(self) -> None:
        low, high = np.asarray(self.low, float), np.asarray(self.high, float)
        if low.shape != high.shape or low.ndim != 1 or low.size == 0:
            raise ValueError(f"outcome box needs low and high of one equal size, got "
                             f"{self.low!r} and {self.high!r}")
        if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high)) and np.all(high > low)):
            raise ValueError(f"outcome box must be finite with high > low, got {self.low!r}, "
                             f"{self.high!r}")
        if not (math.isfinite(self.noise) and self.noise > 0.0):
            raise ValueError(f"outcome noise must be a finite number > 0, got {self.noise!r}")

    @classmethod
    def box(cls, low: Any, high: Any, noise: float) -> WorldScale:
        return cls(tuple(float(v) for v in np.ravel(low)), tuple(float(v) for v in
                                                              np.ravel(high)), float(noise))

    @property
    def noise_rms(self) -> float:
        """The root-mean-square distance of one execution's outcome from the mean, for
        isotropic Gaussian noise of the declared mean distance (2-D: 2 / sqrt(pi) times it):
        the noise part of a model's squared prediction error."""
        d = self.dim
        mean_over_sigma = math.sqrt(2.0) * math.exp(math.lgamma((d + 1) / 2) - math.lgamma(d / 2))
        return float(self.noise * math.sqrt(d) / mean_over_sigma)

    @property
    def dim(self) -> int:
        return len(self.low)

    @property
    def low_array(self) -> np.ndarray:
        return np.asarray(self.low, dtype=float)

    @property
    def high_array(self) -> np.ndarray:
        return np.asarray(self.high, dtype=float)

    @property
    def centre(self) -> np.ndarray:
        return 0.5 * (self.low_array + self.high_array)

    @property
    def size(self) -> float:
        """The box's largest side: the unit of distances that scale with the space."""
        return float(np.max(self.high_array - self.low_array))

    @property
    def diagonal(self) -> float:
        """The largest distance between two points of the box."""
        return portable.norm(self.high_array - self.low_array)

    def clip(self, point: np.ndarray) -> np.ndarray:
        return np.clip(np.asarray(point, dtype=float), self.low_array, self.high_array)

    def contains(self, point: np.ndarray) -> bool:
        p = np.asarray(point, dtype=float)
        return bool(p.shape == (self.dim,) and np.all(p >= self.low_array)
                    and np.all(p <= self.high_array))


def unit_box(dim: int, noise: float) -> WorldScale:
    """[-1, 1]^dim, the normalised outcome space of the fishing world."""
    return WorldScale((-1.0,) * dim, (1.0,) * dim, noise)
