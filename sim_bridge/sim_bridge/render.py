"""Pictures of a cast: the world's own cast, drawn frame by frame with pybullet's TinyRenderer.

Why this way:
- The cast is the world's: ``record_cast`` runs ``FishingWorld.execute`` itself and only
  watches it, through a stand-in for the ``pybullet`` module seen by fishing_world.py whose
  ``stepSimulation`` also notes where every link is every few steps. Nothing in the physics is
  changed or copied (a test checks the outcome is the one ``execute`` gives); after the reel
  opens the hook flies in closed form, and its path is the world's formula, evaluated at the
  frames' times (a test checks it ends at the world's landing point).
- The robot model has no visual shapes (it is built for speed: rod_urdf.py), so the frames are
  drawn in a second DIRECT client that holds only pictures: capsules placed along the recorded
  links, a textured lake (water and land as lake.py says), the pier, the hook and its path.
  The physics client is never touched by the drawing.
- TinyRenderer is pybullet's software renderer: it needs no display or GPU and works in
  DIRECT mode, on any machine the project runs on.

``render_cast(action)`` gives the frames (two views side by side: the arm and rod close up,
the lake from above) and the cast's result; ``save_gif`` writes them as an animated GIF.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pybullet as pb

from sim_bridge import fishing_world, scaling
from sim_bridge.fishing_world import AIR_DRAG, GRAVITY, WATER_Z, CastResult, FishingWorld, Status
from sim_bridge.lake import DEFAULT_LAKE, Lake

FPS = 25


@dataclass
class CastRecording:
    """Where every link was, at the frames' times, and what the cast gave."""

    times: np.ndarray  # (F,) s from the start of the motion
    links: np.ndarray  # (F, L, 3) link frame origins (world, m); the base is link 0
    parents: list[int]  # parent (index in ``links``) of each link; -1 for the base
    hook: np.ndarray  # (F, 3) the hook (m)
    attached: np.ndarray  # (F,) bool: the hook still hangs on the line (before release)
    result: CastResult


class _Watcher:
    """Stands in for the pybullet module inside fishing_world.py: the same functions, except
    that stepSimulation also records the links every ``every`` steps."""

    def __init__(self, world: FishingWorld, every: int) -> None:
        self._world, self._every = world, every
        self.steps = 0
        self.samples: list[np.ndarray] = []
        self.sample_steps: list[int] = []

    def __getattr__(self, name: str) -> object:
        return getattr(pb, name)

    def stepSimulation(self, *args: object, **kwargs: object) -> object:
        out = pb.stepSimulation(*args, **kwargs)
        self.steps += 1
        if self.steps % self._every == 0:
            self.samples.append(link_positions(self._world))
            self.sample_steps.append(self.steps)
        return out


def link_positions(world: FishingWorld) -> np.ndarray:
    """The base and every link frame origin, world coordinates (m)."""
    c, b = world._client, world.body
    base = pb.getBasePositionAndOrientation(b, physicsClientId=c)[0]
    n = pb.getNumJoints(b, physicsClientId=c)
    states = pb.getLinkStates(b, list(range(n)), physicsClientId=c)
    return np.array([base, *(s[4] for s in states)], dtype=float)


def record_cast(world: FishingWorld, action: Sequence[float], fps: float = FPS,
                slow: float = 2.0) -> CastRecording:
    """Execute ``action`` in ``world`` (its next cast, its noise) and record it for frames at
    ``fps`` played ``slow`` times slower than real time."""
    every = max(1, round(1.0 / (fps * slow * world.time_step)))
    watcher = _Watcher(world, every)
    c, b = world._client, world.body
    parents = [-1] + [pb.getJointInfo(b, j, physicsClientId=c)[16] + 1
                      for j in range(pb.getNumJoints(b, physicsClientId=c))]
    saved = fishing_world.pb
    fishing_world.pb = watcher
    try:
        result = world.execute(np.asarray(action, dtype=float))
    finally:
        fishing_world.pb = saved
    hook_index = world.hook_link + 1
    links = list(watcher.samples)
    times = [s * world.time_step for s in watcher.sample_steps]
    attached = [True] * len(links)
    if (result.status in (Status.OK, Status.NO_CONTACT) and math.isfinite(result.release_time)
            and math.isfinite(result.touch_time)):
        # The reel opened: the arm stays where the last step left it (the world's state now),
        # the hook flies by the world's closed form until it touches down.
        state = pb.getLinkState(b, world.hook_link, computeLinkVelocity=1, physicsClientId=c)
        p0, v0 = np.array(state[4]), np.array(state[6])
        last = link_positions(world)
        flight = result.touch_time - result.release_time
        dt = every * world.time_step
        for t in [*np.arange(dt, flight, dt), flight]:
            frame = last.copy()
            frame[hook_index] = free_flight_point(p0, v0, t)
            links.append(frame)
            times.append(result.release_time + t)
            attached.append(False)
    if not links:  # refused or failed at once: one still frame of the start pose
        links, times, attached = [link_positions(world)], [0.0], [True]
    links_array = np.array(links)
    return CastRecording(np.array(times), links_array, parents, links_array[:, hook_index],
                         np.array(attached), result)


def free_flight_point(p0: np.ndarray, v0: np.ndarray, t: float) -> np.ndarray:
    """The hook t s after release, by fishing_world.free_flight_touch's formula."""
    k, g = AIR_DRAG, GRAVITY
    e = -math.expm1(-k * t) / k
    return np.array([p0[0] + v0[0] * e, p0[1] + v0[1] * e,
                     p0[2] + (v0[2] + g / k) * e - g * t / k])


# --- drawing ---------------------------------------------------------------------------------

ARM_COLOUR = (0.78, 0.80, 0.84, 1.0)
ROD_COLOUR = (0.95, 0.80, 0.20, 1.0)
LINE_COLOUR = (0.95, 0.95, 0.95, 1.0)
HOOK_COLOUR = (0.9, 0.1, 0.1, 1.0)
TRAIL_COLOUR = (0.95, 0.45, 0.05, 1.0)


class CastPainter:
    """A DIRECT client holding only pictures of the world; draws recorded frames."""

    def __init__(self, recording: CastRecording, size: tuple[int, int] = (320, 240),
                 lake: Lake | None = None) -> None:
        self.rec, self.size = recording, size
        self.client = pb.connect(pb.DIRECT)
        self._bodies: list[tuple[int, int, int]] = []  # (body, parent, child) per segment
        self._trail: list[int] = []
        self._texture_file = ""
        try:
            self._build(lake or DEFAULT_LAKE)
        except Exception:
            self.close()
            raise

    def close(self) -> None:
        if self.client is not None and pb.isConnected(self.client):
            pb.disconnect(self.client)
        self.client = None
        if self._texture_file:
            os.unlink(self._texture_file)
            self._texture_file = ""

    def _build(self, lake: Lake) -> None:
        c, first = self.client, self.rec.links[0]
        x0, x1, y0, y1 = scaling.OUTCOME_BOX
        self._add_lake(lake, x0, x1, y0, y1)
        pier = pb.createVisualShape(pb.GEOM_BOX, halfExtents=[0.25, 0.25, -WATER_Z / 2],
                                    rgbaColor=[0.45, 0.33, 0.22, 1], physicsClientId=c)
        pb.createMultiBody(0, -1, pier, [-0.1, 0, WATER_Z / 2], physicsClientId=c)
        n_arm = 7  # base + the six arm links; then rod (handle, bends), line, hook
        hook = len(first) - 1
        for child, parent in enumerate(self.rec.parents):
            if parent < 0:
                continue
            length = float(np.linalg.norm(first[child] - first[parent]))
            if length < 1e-3:
                continue
            if child == hook:
                colour, radius = LINE_COLOUR, 0.008
            elif child <= n_arm - 1:
                colour, radius = ARM_COLOUR, 0.045
            else:
                colour, radius = ROD_COLOUR, 0.022
            shape = pb.createVisualShape(pb.GEOM_CAPSULE, radius=radius, length=length,
                                         rgbaColor=colour, physicsClientId=c)
            self._bodies.append((pb.createMultiBody(0, -1, shape, physicsClientId=c),
                                 parent, child))
        ball = pb.createVisualShape(pb.GEOM_SPHERE, radius=0.06, rgbaColor=HOOK_COLOUR,
                                    physicsClientId=c)
        self._hook = pb.createMultiBody(0, -1, ball, physicsClientId=c)
        self._dot = pb.createVisualShape(pb.GEOM_SPHERE, radius=0.1, rgbaColor=TRAIL_COLOUR,
                                         physicsClientId=c)
        # The close-up looks from behind the cast, so the hook flies away from the camera.
        end = self.rec.hook[-1, :2]
        away = end / np.linalg.norm(end) if np.linalg.norm(end) > 0.5 else np.array([1.0, 0.0])
        side = np.array([-away[1], away[0]])
        self._eye = [*(-2.6 * away + 1.2 * side).tolist(), 1.4]
        self._target = [*(0.6 * away).tolist(), -0.3]
        if self.rec.result.world_point is not None:  # where it came down: a disc
            landed = self.rec.result.status == Status.OK
            disc = pb.createVisualShape(
                pb.GEOM_CYLINDER, radius=0.35, length=0.02,
                rgbaColor=[1, 1, 1, 1] if landed else [0.8, 0.1, 0.1, 1], physicsClientId=c)
            self._landing = (disc, [*self.rec.result.world_point.tolist(), WATER_Z + 0.02])
        else:
            self._landing = None

    def _add_lake(self, lake: Lake, x0: float, x1: float, y0: float, y1: float) -> None:
        from PIL import Image

        c, n = self.client, 256
        xs = x0 + (np.arange(n) + 0.5) / n * (x1 - x0)
        ys = y1 - (np.arange(n) + 0.5) / n * (y1 - y0)  # image row 0 is the far (+y) edge
        gx, gy = np.meshgrid(xs, ys)
        water = lake.is_water(np.column_stack([gx.ravel(), gy.ravel()])).reshape(n, n)
        rgb = np.where(water[..., None], np.array([70, 130, 200], np.uint8),
                       np.array([150, 170, 100], np.uint8)).astype(np.uint8)
        fd, self._texture_file = tempfile.mkstemp(suffix=".png", prefix="lake_")
        os.close(fd)
        Image.fromarray(rgb, "RGB").save(self._texture_file)
        # One quad with exact texture coordinates (a box would tile the image on every face).
        z = WATER_Z
        vertices = [[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]]
        uvs = [[0, 0], [1, 0], [1, 1], [0, 1]]  # TinyRenderer: v = 0 is the bottom row
        shape = pb.createVisualShape(pb.GEOM_MESH, vertices=vertices, indices=[0, 1, 2, 0, 2, 3],
                                     uvs=uvs, normals=[[0, 0, 1]] * 4, physicsClientId=c)
        body = pb.createMultiBody(0, -1, shape, physicsClientId=c)
        texture = pb.loadTexture(self._texture_file, physicsClientId=c)
        pb.changeVisualShape(body, -1, textureUniqueId=texture, rgbaColor=[1, 1, 1, 1],
                             physicsClientId=c)

    def _place(self, frame: int) -> None:
        c, links = self.client, self.rec.links[frame]
        for body, parent, child in self._bodies:
            a, b = links[parent], links[child]
            if child == len(links) - 1 and not self.rec.attached[frame]:
                pb.resetBasePositionAndOrientation(body, [0, 0, -100], [0, 0, 0, 1],
                                                   physicsClientId=c)  # the line ran out
                continue
            pb.resetBasePositionAndOrientation(body, ((a + b) / 2).tolist(), _z_to(b - a),
                                               physicsClientId=c)
        hook = self.rec.hook[frame]
        pb.resetBasePositionAndOrientation(self._hook, hook.tolist(), [0, 0, 0, 1],
                                           physicsClientId=c)
        if not self.rec.attached[frame]:
            self._trail.append(pb.createMultiBody(0, -1, self._dot, hook.tolist(),
                                                  physicsClientId=c))
        if frame == len(self.rec.times) - 1 and self._landing is not None:
            shape, where = self._landing
            pb.createMultiBody(0, -1, shape, where, physicsClientId=c)

    def _view(self, eye: Sequence[float], target: Sequence[float], fov: float,
              up: Sequence[float] = (0, 0, 1)) -> np.ndarray:
        w, h = self.size
        view = pb.computeViewMatrix(eye, target, up, physicsClientId=self.client)
        projection = pb.computeProjectionMatrixFOV(fov, w / h, 0.1, 60.0,
                                                   physicsClientId=self.client)
        image = pb.getCameraImage(w, h, view, projection, renderer=pb.ER_TINY_RENDERER,
                                  lightDirection=[-3, -2, 6], shadow=0,
                                  physicsClientId=self.client)[2]
        return np.asarray(image, dtype=np.uint8).reshape(h, w, 4)[..., :3]

    def frames(self) -> list[np.ndarray]:
        """Each frame: the arm close up (left) beside the lake from above (right)."""
        out = []
        for k in range(len(self.rec.times)):
            self._place(k)
            near = self._view(self._eye, self._target, 55)
            # From above, x to the right and y up: the outcome space as the page draws it.
            lake = self._view([0.0, 0.0, 17.0], [0.0, 0.0, WATER_Z], 52, up=(0, 1, 0))
            out.append(np.concatenate([near, lake], axis=1))
        return out


def _z_to(direction: np.ndarray) -> list[float]:
    """The quaternion that turns +z onto ``direction`` (a capsule's axis)."""
    d = direction / (np.linalg.norm(direction) or 1.0)
    axis = np.cross([0.0, 0.0, 1.0], d)
    s = float(np.linalg.norm(axis))
    angle = math.atan2(s, float(d[2]))
    if s < 1e-9:
        return [0.0, 0.0, 0.0, 1.0] if d[2] > 0 else [1.0, 0.0, 0.0, 0.0]
    axis /= s
    half = angle / 2
    return [*(axis * math.sin(half)).tolist(), math.cos(half)]


def render_cast(action: Sequence[float], seed: int = 0, size: tuple[int, int] = (320, 240),
                fps: float = FPS, slow: float = 2.0,
                world: FishingWorld | None = None) -> tuple[list[np.ndarray], CastResult]:
    """The frames of one cast of ``action`` (the world's first cast for ``seed``)."""
    own = world is None
    world = world or FishingWorld(seed=seed)
    try:
        recording = record_cast(world, action, fps, slow)
    finally:
        if own:
            world.close()
    painter = CastPainter(recording, size)
    try:
        return painter.frames(), recording.result
    finally:
        painter.close()


def save_gif(frames: Sequence[np.ndarray], path: str | os.PathLike[str], fps: float = FPS,
             hold: float = 1.0, colours: int = 64) -> None:
    """An animated GIF that loops, the last frame held ``hold`` seconds."""
    from PIL import Image

    if not frames:
        raise ValueError("no frames to save")
    images = [Image.fromarray(f).quantize(colours, method=Image.Quantize.MEDIANCUT,
                                          dither=Image.Dither.NONE) for f in frames]
    durations = [round(1000 / fps)] * len(images)
    durations[-1] += round(1000 * hold)
    images[0].save(path, save_all=True, append_images=images[1:], duration=durations, loop=0,
                   optimize=True, disposal=1)
