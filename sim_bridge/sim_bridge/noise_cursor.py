"""Movement k of a run gets the k-th draw of its seed's noise stream, whatever came before.

Why: the fishing world draws each cast's motor noise from one stream (24 normals per valid
cast), so the noise a movement gets is the number of casts made before it. An uninterrupted
run makes movement k as its k-th cast, which the single-process runner does too. A simulator
killed mid-run and restarted by the launcher starts its stream again at the seed, and a
movement executed again after a lost answer is a cast more: without this cursor, every
movement after either would get other noise than the same seed's uninterrupted run (the chaos
soak found it: benchmarks/chaos_soak.py), and a restarted simulator would replay noise the run
had already used. The cursor moves the stream to where movement k's noise starts before the
cast: forward by drawing what the missing casts would have drawn, or back by starting again
at the seed. An uninterrupted run never moves it, so its movements do not change.

A cast not recorded (a human teacher measuring an action, record=false) draws from where the
stream is; the next movement puts it back.

Moving forward costs what the skipped casts would have drawn (24 normals each: about a second
per million casts on these machines), so a movement index far ahead of the stream, which a
forged request can name (the live-node fuzzer found one: index 40,427,983 held the simulator
for half a minute per request), is refused rather than served late: at most ``MAX_SKIP`` casts
are skipped at once. A run's simulator restarted past movement one million therefore cannot
go on (it says so, and the run fails); the cure is a world whose stream can be put at cast k
at once (a counter-based stream per cast), which changes every run's noise and so waits for
the next change of the world.
"""

from __future__ import annotations

import numpy as np

from sim_bridge import scaling
from sim_bridge.fishing_world import CastResult, FishingWorld, Status

CHUNK = 65_536  # casts' worth of draws skipped per call: bounded memory for any index
MAX_SKIP = 1_000_000  # casts skipped at most to reach a movement (about a second)


class TooFarAhead(ValueError):
    """A movement index the stream cannot reach in bounded time (MAX_SKIP)."""


class NoiseCursor:
    """Casts in a world with its noise stream kept at the movement being cast."""

    def __init__(self, world: FishingWorld) -> None:
        self.world = world
        self.casts = 0  # valid casts drawn from the stream since the seed

    def execute(self, action: np.ndarray, movement_index: int | None = None) -> CastResult:
        """Cast `action`; with `movement_index` (1-based), with that movement's noise. An index
        too far ahead (MAX_SKIP) is refused like a bad action: nothing drawn, nothing cast."""
        if movement_index is not None:
            try:
                self.move_to(movement_index)
            except TooFarAhead as error:
                return CastResult(status=Status.INVALID_ACTION, message=str(error))
        result = self.world.execute(action)
        if result.status != Status.INVALID_ACTION:  # a refused action draws nothing
            self.casts += 1
        return result

    def move_to(self, movement_index: int) -> None:
        """Put the stream where movement `movement_index` draws its noise."""
        wanted = max(int(movement_index) - 1, 0)
        start = self.casts if wanted >= self.casts else 0
        if wanted - start > MAX_SKIP:
            raise TooFarAhead(
                f"movement {movement_index} is {wanted - start} casts ahead of the noise "
                f"stream (at cast {self.casts}); at most {MAX_SKIP} are skipped: not this "
                "run's movement")
        if wanted < self.casts:
            self.world.reseed(self.world.seed)
            self.casts = 0
        while self.casts < wanted:
            skipped = min(wanted - self.casts, CHUNK)
            self.world.rng.standard_normal((skipped, scaling.ACTION_DIM))
            self.casts += skipped
