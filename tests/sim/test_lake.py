"""The shoreline: the box, the isolated pond's place and isolation, the point-in-shape tests."""

import numpy as np

from sim_bridge import lake, scaling
from sim_bridge.data_files import ISOLATED_REGION, in_isolated_region


def test_outcome_box_is_the_water_bounding_box() -> None:
    np.testing.assert_allclose(lake.water_bounding_box(), scaling.OUTCOME_BOX)


def test_isolated_region_is_the_pond() -> None:
    np.testing.assert_allclose(ISOLATED_REGION["centre"], (-0.85, -0.25), atol=1e-12)
    r = ISOLATED_REGION["radius"]
    assert 0.05 < r < 0.2
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    ring = np.c_[np.cos(t), np.sin(t)]
    centre = np.array(ISOLATED_REGION["centre"])
    inside = scaling.outcome_to_world(centre + 0.98 * r * ring)
    assert np.all(lake.water_body(inside) == lake.ISOLATED_POND)
    assert np.all(in_isolated_region(centre + 0.98 * r * ring))
    assert not np.any(in_isolated_region(centre + 1.02 * r * ring))


def test_pond_is_cut_off_by_land() -> None:
    """Every point between 0.05 m and 2.5 m outside the pond's shore is land."""
    cx, cy, r = lake.POND
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    for d in np.linspace(0.05, 2.5, 50):
        ring = np.c_[cx + (r + d) * np.cos(t), cy + (r + d) * np.sin(t)]
        assert np.all(lake.water_body(ring) == lake.LAND)


def test_water_shapes() -> None:
    pts = np.array([[0.0, 0.0], [1.0, 0.3], [-8.4, 1.8], [8.4, 0.6], [0.3, 8.4], [2.4, -8.4],
                    [-8.6, 1.8], [-3.0, -3.0], [-6.0, 6.0], [6.0, -6.0], [-7.225, -2.125]])
    expected = [1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 2]
    assert lake.water_body(pts).tolist() == expected
    assert lake.is_water(np.array([0.0, 0.0]))  # a single point works too
    assert lake.water_body(pts.reshape(11, 1, 2)).shape == (11, 1)


def test_scalar_point_test_agrees_with_the_vectorised_one() -> None:
    """``Lake.body_at`` (one point, plain floats, used once per cast) gives ``water_body``'s
    answer everywhere: random points, the shapes' vertices and points just off them."""
    rng = np.random.default_rng(7)
    verts = np.vstack(list(lake.ARMS.values()))
    cx, cy, r = lake.POND
    pts = np.vstack([rng.uniform(-9.0, 9.0, (20000, 2)), verts, verts + np.array([0.0, 1e-12]),
                     verts - np.array([1e-9, 0.0]), [[cx + r, cy], [cx, cy - r]]])
    for lk in (lake.DEFAULT_LAKE, lake.Lake(pond_radius=0.3)):
        scalar = [lk.body_at(float(x), float(y)) for x, y in pts]
        assert scalar == lk.water_body(pts).tolist()


def test_each_named_part_of_the_lake_is_told_apart():
    from sim_bridge.lake import DEFAULT_LAKE, PARTS

    points = {"basin": (1.0, 0.3), "west": (-8.0, 1.8), "east": (8.0, 0.6),
              "north": (0.3, 8.0), "south": (2.4, -8.0), "pond": (-7.225, -2.125),
              "land": (-5.0, -6.0)}
    assert {DEFAULT_LAKE.part_at(x, y) for x, y in points.values()} == {*PARTS, "land"}
    for name, (x, y) in points.items():
        assert DEFAULT_LAKE.part_at(x, y) == name
    # Where an arm's root overlaps the basin, the point is the basin's.
    assert DEFAULT_LAKE.part_at(-1.8, 1.0) == "basin"
