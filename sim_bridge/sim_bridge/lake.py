"""The shoreline of the fishing world: where a hook that touches down is in water, or on land.

Why a shoreline: a flat, endless water plane let every cast land, so random casts formed one round
blob and the reached points filled their whole bounding box; the paper's problem has a natural
landing zone, a thin reachable shape (129 of the 26 x 16 benchmark cells) and an isolated region
that random actions almost never reach. Here the water is a reservoir flooded into valleys:

- the main basin, an ellipse around the pier (the robot base, at the origin), covers the natural
  landing zone where random casts pile up;
- four drowned valleys (arms, polygons) run out to 8.5 m west, east, north and south of the basin;
- a small round pond, the isolated region, lies far behind and to the right of the robot, cut
  off from the main lake by more than 2.5 m of land. It is reachable, but only by a tiny part of
  the action space (about 0.05 % of uniformly random actions, README_world.md: a random run of
  5000 movements lands there about 2-3 times), yet some actions land there cast after cast, so
  a teacher can show it. Since land surrounds it, casts that land near it are not outcomes: a
  learner cannot creep towards it from the lake's shore.

The land is a flat bank at the water's level (``WATER_Z``): the hook's first touch of that level is
either a water landing (the outcome) or a land landing (status NO_CONTACT, no outcome). All shapes
are in world metres (x forward from the robot, y to its left); their union's bounding box is
``scaling.OUTCOME_BOX``, so the normalised outcomes of water landings cover [-1, 1]^2 and the pond
sits at (-0.85, -0.25) in normalised units (the paper's isolated region: around (-0.5, -0.25);
ours is farther out, where random casts are rarer, docs/isolated_region.md).
"""

from __future__ import annotations

import numpy as np

from sim_bridge import scaling

LAND, MAIN_LAKE, ISOLATED_POND = 0, 1, 2

# Ellipses: (centre x, centre y, semi-axis x, semi-axis y), metres.
BASIN = (1.0, 0.3, 3.5, 3.3)
# Polygons (x, y) in metres, counter-clockwise or not; each overlaps the basin at its root.
ARMS: dict[str, np.ndarray] = {
    "west": np.array([(-1.8, 0.6), (-4.5, 1.0), (-8.5, 1.3), (-8.5, 2.3), (-4.5, 2.2),
                      (-1.5, 2.1)]),
    "east": np.array([(3.8, -0.7), (6.0, -0.2), (8.5, 0.2), (8.5, 1.1), (6.0, 0.9),
                      (3.8, 0.7)]),
    "north": np.array([(-0.2, 3.0), (0.2, 5.5), (-0.3, 8.5), (0.8, 8.5), (1.3, 5.5),
                       (1.2, 3.0)]),
    "south": np.array([(1.2, -2.5), (2.0, -5.5), (1.9, -8.5), (2.9, -8.5), (3.0, -5.5),
                       (2.6, -2.5)]),
}
_ARM_TUPLES = tuple(tuple((float(px), float(py)) for px, py in poly) for poly in ARMS.values())
# The isolated pond: a disc (centre x, centre y, radius), metres. Chosen on 30,000 random casts
# (seed 101) for a share of random actions near 0.05 % and a radius (0.75 m) well above the cast
# noise of repeatable actions; its share measured on other casts: README_world.md.
POND = (-7.225, -2.125, 0.75)


PARTS = ("basin", *ARMS, "pond")
"""The lake's named parts: the basin around the pier, its four arms (beyond the basin) and the
isolated pond. SGIM-ACTS's teachers each know some of them (core/experts.py)."""


def _in_ellipse(xy: np.ndarray, e: tuple[float, float, float, float]) -> np.ndarray:
    cx, cy, a, b = e
    return ((xy[..., 0] - cx) / a) ** 2 + ((xy[..., 1] - cy) / b) ** 2 <= 1.0


def _in_polygon(xy: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd ray casting, vectorised over points (..., 2)."""
    x, y = xy[..., 0], xy[..., 1]
    inside = np.zeros(np.shape(x), dtype=bool)
    for (x1, y1), (x2, y2) in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        crosses = (y1 > y) != (y2 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
        inside ^= crosses & (x < x_cross)
    return inside


def _in_disc(xy: np.ndarray, cx: float, cy: float, r: float) -> np.ndarray:
    return (xy[..., 0] - cx) ** 2 + (xy[..., 1] - cy) ** 2 <= r * r


def _in_main_lake(xy: np.ndarray) -> np.ndarray:
    main = _in_ellipse(xy, BASIN)
    for poly in ARMS.values():
        main |= _in_polygon(xy, poly)
    return main


def _point_in_polygon(x: float, y: float, poly: tuple[tuple[float, float], ...]) -> bool:
    """``_in_polygon`` for one point in plain floats: the same operations in the same order (so
    the same answer, bit for bit, a test checks it), without numpy's per-call overhead."""
    inside = False
    x1, y1 = poly[-1]
    for x2, y2 in poly:
        # edge from (x1, y1) to (x2, y2), as np.roll(poly, -1) pairs them
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
        x1, y1 = x2, y2
    return inside


def water_bounding_box() -> np.ndarray:
    """[x_min, x_max, y_min, y_max] of the union of the default water shapes (= OUTCOME_BOX)."""
    cx, cy, a, b = BASIN
    px, py, r = POND
    pts = np.vstack([*ARMS.values(), [(cx - a, cy - b), (cx + a, cy + b)],
                     [(px - r, py - r), (px + r, py + r)]])
    return np.array([pts[:, 0].min(), pts[:, 0].max(), pts[:, 1].min(), pts[:, 1].max()])


class Lake:
    """The water of one world: the fixed main lake (basin and arms) and an isolated pond.

    Why a parameter: how rarely random actions reach the pond (its isolation in action space)
    is set by the pond's size and place; ``Lake()`` is the default world (``POND``), and
    ``Lake(pond_radius=0.3)`` a world whose pond is smaller but at the same place, so the main
    lake, the outcome map (``scaling.OUTCOME_BOX``) and every stored data file stay valid for
    it. A pond may be moved (``pond_centre``) but must stay inside the outcome box and apart
    from the main lake (at least ``MIN_LAND`` metres of land); otherwise ``ValueError``.
    """

    MIN_LAND = 0.3  # m: the least land between the pond and the main lake

    def __init__(self, pond_radius: float = POND[2],
                 pond_centre: tuple[float, float] = (POND[0], POND[1])) -> None:
        r, (cx, cy) = float(pond_radius), (float(pond_centre[0]), float(pond_centre[1]))
        if not (np.isfinite(r) and r > 0.0 and np.isfinite(cx) and np.isfinite(cy)):
            raise ValueError("pond_radius must be a finite number > 0 and its centre finite")
        box = scaling.OUTCOME_BOX
        if cx - r < box[0] or cx + r > box[1] or cy - r < box[2] or cy + r > box[3]:
            raise ValueError(f"the pond must lie inside the outcome box {list(box)}")
        self.pond = (cx, cy, r)
        t = np.linspace(0.0, 2.0 * np.pi, 720, endpoint=False)
        disc = np.concatenate([np.c_[cx + d * np.cos(t), cy + d * np.sin(t)]
                               for d in np.linspace(0.0, r + self.MIN_LAND, 24)])
        if np.any(_in_main_lake(disc)):
            raise ValueError(f"the pond must be at least {self.MIN_LAND} m of land away from "
                             "the main lake")

    def __repr__(self) -> str:
        cx, cy, r = self.pond
        return f"Lake(pond_radius={r!r}, pond_centre=({cx!r}, {cy!r}))"

    @property
    def is_default(self) -> bool:
        return self.pond == POND

    def water_body(self, xy: np.ndarray) -> np.ndarray:
        """LAND, MAIN_LAKE or ISOLATED_POND for world points (..., 2) in metres."""
        xy = np.asarray(xy, dtype=float)
        out = np.where(_in_main_lake(xy), MAIN_LAKE, LAND)
        return np.where(_in_disc(xy, *self.pond), ISOLATED_POND, out)

    def is_water(self, xy: np.ndarray) -> np.ndarray:
        """True where world points (..., 2) lie on water."""
        return self.water_body(xy) != LAND

    def body_at(self, x: float, y: float) -> int:
        """``water_body`` of one point (metres), in plain floats: the world asks it once per cast,
        where numpy's per-call overhead cost 0.24 ms; same answers (tested)."""
        cx, cy, r = self.pond
        if (x - cx) ** 2 + (y - cy) ** 2 <= r * r:
            return ISOLATED_POND
        bx, by, a, b = BASIN
        if ((x - bx) / a) ** 2 + ((y - by) / b) ** 2 <= 1.0:
            return MAIN_LAKE
        if any(_point_in_polygon(x, y, poly) for poly in _ARM_TUPLES):
            return MAIN_LAKE
        return LAND

    def part_at(self, x: float, y: float) -> str:
        """The named part (PARTS) a world point (metres) lies in, or "land": an arm is the
        valley beyond the basin's ellipse, where the two overlap the point is the basin's."""
        body = self.body_at(x, y)
        if body == ISOLATED_POND:
            return "pond"
        if body == LAND:
            return "land"
        bx, by, a, b = BASIN
        if ((x - bx) / a) ** 2 + ((y - by) / b) ** 2 <= 1.0:
            return "basin"
        return next(name for name, poly in zip(ARMS, _ARM_TUPLES, strict=True)
                    if _point_in_polygon(x, y, poly))

    def part_of_outcome(self, outcome) -> str:
        """The named part a normalised outcome (the learner's units) lies in (part_at)."""
        return self.part_at(*(float(v) for v in scaling.outcome_to_world(outcome)))

    def isolated_centre_radius(self) -> tuple[np.ndarray, float]:
        """The pond in normalised outcome units: centre (2,) and radius."""
        box = scaling.OUTCOME_BOX
        centre = scaling.world_to_outcome(np.array(self.pond[:2]))
        scale = 2.0 / np.array([box[1] - box[0], box[3] - box[2]])
        # The box is square, so the pond is a circle in normalised units too.
        return centre, float(self.pond[2] * scale.max())

    def isolated_region(self) -> dict[str, object]:
        """``{"centre": (x, y), "radius": r}`` of the pond, normalised outcome units."""
        centre, radius = self.isolated_centre_radius()
        return {"centre": tuple(float(v) for v in centre), "radius": radius}

    def in_isolated_region(self, outcomes: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """True for normalised outcomes (..., 2) within the pond's radius + ``margin``."""
        centre, radius = self.isolated_centre_radius()
        u = np.asarray(outcomes, dtype=float)
        return np.linalg.norm(u - centre, axis=-1) <= radius + margin


DEFAULT_LAKE = Lake()


def lake_with_pond_radius(pond_radius: float | None) -> Lake:
    """The default lake, or one whose pond (same centre) has this radius in metres."""
    return DEFAULT_LAKE if pond_radius is None else Lake(pond_radius=pond_radius)


def isolated_region(lake: Lake | None = None) -> dict[str, object]:
    """The isolated region (normalised units) of ``lake`` (default: the default lake)."""
    return (lake or DEFAULT_LAKE).isolated_region()


def water_body(xy: np.ndarray) -> np.ndarray:
    """LAND, MAIN_LAKE or ISOLATED_POND for world points (..., 2) in metres (default lake)."""
    return DEFAULT_LAKE.water_body(xy)


def is_water(xy: np.ndarray) -> np.ndarray:
    """True where world points (..., 2) lie on water (default lake)."""
    return DEFAULT_LAKE.is_water(xy)


# The isolated region in normalised outcome units: centre (-0.85, -0.25), radius 0.088 (the pond).
ISOLATED_CENTRE, ISOLATED_RADIUS = DEFAULT_LAKE.isolated_centre_radius()
ISOLATED_REGION = isolated_region()


def in_isolated_region(outcomes: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """True for normalised outcomes (..., 2) within ``ISOLATED_RADIUS + margin`` of its centre."""
    return DEFAULT_LAKE.in_isolated_region(outcomes, margin)


def draw_shoreline(ax: object, resolution: int = 400, lake: Lake | None = None,
                   **kw: object) -> None:
    """Draw the shoreline (the water's edge, normalised units) on a matplotlib axis."""
    g = np.linspace(-1.0, 1.0, resolution)
    ux, uy = np.meshgrid(g, g)
    world = scaling.outcome_to_world(np.stack([ux, uy], axis=-1))
    wet = (lake or DEFAULT_LAKE).is_water(world).astype(float)
    style = {"colors": "tab:red", "linewidths": 0.8} | kw
    ax.contour(ux, uy, wet, levels=[0.5], **style)  # type: ignore[attr-defined]
