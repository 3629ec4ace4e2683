"""The live picture as visualization_msgs/MarkerArray, for rviz2 and Foxglove.

Everything lies in the plane z = 0 of the frame ``outcome_space``, in outcome units
([-1, 1]^2, x right, y up): regions slightly below (z = -0.01), landings on it, goals above.
Each topic's array starts with DELETEALL where it replaces the whole picture, so a viewer that
joins late, or a replay that seeks, shows the right state at the next full message:

  markers/landings        POINTS coloured by process; between full refreshes (every few
                          seconds) only the new landings, as a new marker id (cheap to send
                          and to record: each landing is sent about twice per run)
  markers/regions         the interest tree's leaves: filled (TRIANGLE_LIST, viridis by
                          interest / highest interest) and outlined (LINE_LIST)
  markers/teaching_goals  SPHERE_LIST, green reached / red unreached, with their teaching-set
                          index as text (the number `teach N` and the page use)
  markers/current_goal    a white SPHERE at the goal of the latest movement or goal choice
"""

from __future__ import annotations

from geometry_msgs.msg import Point, Vector3
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from sgim_nodes.view.picture import (
    GOAL_COLOUR,
    PROCESS_COLOURS,
    REACHED_COLOUR,
    UNREACHED_COLOUR,
    LivePicture,
    interest_colour,
)

FRAME = "outcome_space"
LANDING_SIZE = 0.02
GOAL_SIZE = 0.06
TEACHING_SIZE = 0.05


def colour(rgb: tuple[int, int, int], alpha: float = 1.0) -> ColorRGBA:
    return ColorRGBA(r=rgb[0] / 255.0, g=rgb[1] / 255.0, b=rgb[2] / 255.0, a=float(alpha))


def _marker(ns: str, marker_id: int, kind: int, stamp, scale: float) -> Marker:
    m = Marker(ns=ns, id=marker_id, type=kind, action=Marker.ADD)
    m.header.frame_id, m.header.stamp = FRAME, stamp
    m.pose.orientation.w = 1.0
    m.scale = Vector3(x=scale, y=scale, z=scale)
    m.frame_locked = False
    return m


def delete_all(stamp) -> Marker:
    m = Marker(action=Marker.DELETEALL)
    m.header.frame_id, m.header.stamp = FRAME, stamp
    return m


def landings(picture: LivePicture, start: int, marker_id: int, stamp) -> Marker:
    """The landings from ``start`` on, as one POINTS marker."""
    m = _marker("landings", marker_id, Marker.POINTS, stamp, LANDING_SIZE)
    grey = (127, 127, 127)
    end = picture.landings
    m.points = [Point(x=x, y=y, z=0.0) for x, y in zip(picture.xs[start:end],
                                                      picture.ys[start:end], strict=True)]
    m.colors = [colour(PROCESS_COLOURS.get(p, grey)) for p in picture.processes[start:end]]
    return m


def landings_full(picture: LivePicture, stamp) -> MarkerArray:
    return MarkerArray(markers=[delete_all(stamp), landings(picture, 0, 0, stamp)])


def regions(picture: LivePicture, stamp) -> MarkerArray:
    fill = _marker("regions", 0, Marker.TRIANGLE_LIST, stamp, 1.0)
    fill.pose.position.z = -0.01
    edges = _marker("regions", 1, Marker.LINE_LIST, stamp, 0.004)
    edges.pose.position.z = -0.009
    edges.color = colour((230, 230, 230), 0.8)
    top = picture.highest_interest()
    for leaf in picture.leaves:
        (x0, y0), (x1, y1) = leaf.low, leaf.high
        c = colour(interest_colour(leaf.interest / top if top > 0 else 0.0), 0.55)
        corners = [Point(x=x0, y=y0), Point(x=x1, y=y0), Point(x=x1, y=y1), Point(x=x0, y=y1)]
        fill.points += [corners[0], corners[1], corners[2], corners[0], corners[2], corners[3]]
        fill.colors += [c] * 6
        for a, b in ((0, 1), (1, 2), (2, 3), (3, 0)):
            edges.points += [corners[a], corners[b]]
    markers = [delete_all(stamp)]
    if picture.leaves:
        markers += [fill, edges]
    return MarkerArray(markers=markers)


def teaching_goals(picture: LivePicture, stamp) -> MarkerArray:
    spheres = _marker("teaching_goals", 0, Marker.SPHERE_LIST, stamp, TEACHING_SIZE)
    spheres.pose.position.z = 0.01
    markers = [delete_all(stamp), spheres]
    for i, (outcome, reached) in enumerate(zip(picture.teacher.outcomes, picture.reached,
                                               strict=True)):
        x, y = float(outcome[0]), float(outcome[1])
        spheres.points.append(Point(x=x, y=y, z=0.0))
        spheres.colors.append(colour(REACHED_COLOUR if reached else UNREACHED_COLOUR))
        label = _marker("teaching_labels", i, Marker.TEXT_VIEW_FACING, stamp, 0.05)
        label.pose.position.x, label.pose.position.y, label.pose.position.z = x, y + 0.05, 0.02
        label.color = colour(REACHED_COLOUR if reached else UNREACHED_COLOUR)
        label.text = str(i)
        markers.append(label)
    return MarkerArray(markers=markers)


def current_goal(picture: LivePicture, stamp) -> MarkerArray:
    markers = [delete_all(stamp)]
    if picture.goal is not None:
        m = _marker("current_goal", 0, Marker.SPHERE, stamp, GOAL_SIZE)
        m.pose.position.x, m.pose.position.y, m.pose.position.z = (*picture.goal, 0.02)
        m.color = colour(GOAL_COLOUR, 0.9)
        markers.append(m)
    return MarkerArray(markers=markers)
