"""The shoreline of the fishing world: where a hook that touches down is in water, or on land.

Why a shoreline: a flat, endless water plane let every cast land, so random casts formed one round
blob and the reached points filled their whole bounding box; the paper's problem has a natural
landing zone, a thin reachable shape (129 of the 26 x 16 benchmark cells) and an isolated region
that random actions almost never reach. Here the water is a reservoir flooded into valleys:

- the main basin, an ellipse around the pier (the robot base, at the origin), covers the natural
  landing zone where random casts pile up;
- four drowned valleys (arms, polygons) run out to 8.5 m west, east, north and south of the basin;
- a small round pond, cut off from the basin by at least 1.3 m of land, lies behind and to the
  right of the robot. It is reachable, but only by a small part of the action space (about 0.8 %
  of uniformly random actions, README_world.md), and since land surrounds it, casts that land near
  it are not outcomes: a learner cannot creep towards it from the basin's shore.

The land is a flat bank at the water's level (``WATER_Z``): the hook's first touch of that level is
either a water landing (the outcome) or a land landing (status NO_CONTACT, no outcome). All shapes
are in world metres (x forward from the robot, y to its left); their union's bounding box is
``scaling.OUTCOME_BOX``, so the normalised outcomes of water landings cover [-1, 1]^2 and the pond
sits at (-0.5, -0.25) in normalised units, where the paper's isolated region was.
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
# The isolated pond: a disc (centre x, centre y, radius), metres.
POND = (-4.25, -2.125, 0.95)


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


def _in_pond(xy: np.ndarray) -> np.ndarray:
    cx, cy, r = POND
    return (xy[..., 0] - cx) ** 2 + (xy[..., 1] - cy) ** 2 <= r * r


def water_body(xy: np.ndarray) -> np.ndarray:
    """LAND, MAIN_LAKE or ISOLATED_POND for world points (..., 2) in metres."""
    xy = np.asarray(xy, dtype=float)
    main = _in_ellipse(xy, BASIN)
    for poly in ARMS.values():
        main |= _in_polygon(xy, poly)
    out = np.where(main, MAIN_LAKE, LAND)
    return np.where(_in_pond(xy), ISOLATED_POND, out)


def is_water(xy: np.ndarray) -> np.ndarray:
    """True where world points (..., 2) lie on water."""
    return water_body(xy) != LAND


def water_bounding_box() -> np.ndarray:
    """[x_min, x_max, y_min, y_max] of the union of the water shapes (equals OUTCOME_BOX)."""
    cx, cy, a, b = BASIN
    px, py, r = POND
    pts = np.vstack([*ARMS.values(), [(cx - a, cy - b), (cx + a, cy + b)],
                     [(px - r, py - r), (px + r, py + r)]])
    return np.array([pts[:, 0].min(), pts[:, 0].max(), pts[:, 1].min(), pts[:, 1].max()])


def _isolated_region() -> tuple[np.ndarray, float]:
    box = scaling.OUTCOME_BOX
    centre = scaling.world_to_outcome(np.array(POND[:2]))
    scale = 2.0 / np.array([box[1] - box[0], box[3] - box[2]])
    # The box is square, so the pond is a circle in normalised units too.
    return centre, float(POND[2] * scale.max())


# The isolated region in normalised outcome units: centre (-0.5, -0.25), radius 0.112 (the pond).
ISOLATED_CENTRE, ISOLATED_RADIUS = _isolated_region()
ISOLATED_REGION = {"centre": tuple(float(v) for v in ISOLATED_CENTRE),
                   "radius": ISOLATED_RADIUS}


def in_isolated_region(outcomes: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """True for normalised outcomes (..., 2) within ``ISOLATED_RADIUS + margin`` of its centre."""
    u = np.asarray(outcomes, dtype=float)
    return np.linalg.norm(u - ISOLATED_CENTRE, axis=-1) <= ISOLATED_RADIUS + margin



def draw_shoreline(ax: object, resolution: int = 400, **kw: object) -> None:
    """Draw the shoreline (the water's edge, normalised units) on a matplotlib axis."""
    g = np.linspace(-1.0, 1.0, resolution)
    ux, uy = np.meshgrid(g, g)
    wet = is_water(scaling.outcome_to_world(np.stack([ux, uy], axis=-1))).astype(float)
    style = {"colors": "tab:red", "linewidths": 0.8} | kw
    ax.contour(ux, uy, wet, levels=[0.5], **style)  # type: ignore[attr-defined]
