"""`World`: the walls a simulated robot drives between, and the geometry it needs.

A world is a list of walls, each a straight line segment in metres. Walls
have no thickness: the robot is a circle, and it touches a wall when the
wall comes closer to its centre than its radius. Two pieces of geometry do
all the work: `ray_hit_m` (how far a range sensor sees) and
`distance_to_segment_m` (is the robot touching a wall).

A world is built in code or read from a small JSON file::

    {
      "name": "square room",
      "walls": [[0, 0, 4, 0], [4, 0, 4, 3]],      # x1, y1, x2, y2 in metres
      "boxes": [[1.5, 1.0, 0.5, 0.5]],            # x, y, width, height: 4 walls
      "start": [0.5, 0.5, 0.0],                   # x, y (m), heading (rad)
      "goal": [3.5, 2.5]                          # optional, for lessons
    }

Example::

    world = World.load("examples/rover/room.json")
    world.ray_hit_m(0.5, 0.5, 0.0, max_range_m=5.0)     # 3.5: the east wall
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, NamedTuple, Optional, Sequence, Tuple, Union

from snr.prelude import ComponentError

__all__ = ["Segment", "World", "distance_to_segment_m", "ray_segment_hit_m"]


class Segment(NamedTuple):
    """A wall from (x1, y1) to (x2, y2), in metres.

    Example::

        Segment(0.0, 0.0, 4.0, 0.0)    # 4 m along the x axis
    """

    x1: float
    y1: float
    x2: float
    y2: float


def ray_segment_hit_m(x: float, y: float, dx: float, dy: float, wall: Segment) -> Optional[float]:
    """How far along the ray from (x, y) in unit direction (dx, dy) it meets ``wall``.

    Solves ``(x, y) + t (dx, dy) = A + u (B - A)`` for the distance ``t``
    (0 or more: the ray only looks forward) and the place ``u`` on the
    wall (0 to 1: between its two ends). None if they never meet.

    Example::

        ray_segment_hit_m(0, 0, 1, 0, Segment(2, -1, 2, 1))    # 2.0
    """
    ex, ey = wall.x2 - wall.x1, wall.y2 - wall.y1
    # 2-D cross products; `denominator` is 0 when the ray runs along the wall.
    denominator = dx * ey - dy * ex
    if abs(denominator) < 1e-12:
        return None
    ax, ay = wall.x1 - x, wall.y1 - y
    t = (ax * ey - ay * ex) / denominator
    u = (ax * dy - ay * dx) / denominator
    if t >= 0.0 and 0.0 <= u <= 1.0:
        return t
    return None


def distance_to_segment_m(x: float, y: float, wall: Segment) -> float:
    """The shortest distance from the point (x, y) to ``wall``.

    Project the point on the wall's line, clamp to the wall's two ends, and
    measure to that closest point.

    Example::

        distance_to_segment_m(0, 1, Segment(-1, 0, 1, 0))    # 1.0
        distance_to_segment_m(3, 0, Segment(-1, 0, 1, 0))    # 2.0: past the end
    """
    ex, ey = wall.x2 - wall.x1, wall.y2 - wall.y1
    length_squared = ex * ex + ey * ey
    if length_squared == 0.0:  # a wall that is a single point
        return math.hypot(x - wall.x1, y - wall.y1)
    u = ((x - wall.x1) * ex + (y - wall.y1) * ey) / length_squared
    u = min(1.0, max(0.0, u))
    return math.hypot(x - (wall.x1 + u * ex), y - (wall.y1 + u * ey))


Pose3 = Tuple[float, float, float]


@dataclass
class World:
    """Walls, where the robot starts and (for lessons) where it should go.

    Args:
        walls: the wall segments, in metres.
        start: the robot's starting (x, y, heading in radians).
        goal: an optional (x, y) target for go-to-goal lessons.
        name: shown in the window's title and the log.

    Example::

        world = World.box(4.0, 3.0)          # a 4 m x 3 m room, no furniture
        world.add_box(1.5, 1.0, 0.5, 0.5)    # and a 50 cm crate
    """

    walls: List[Segment] = field(default_factory=list)
    start: Pose3 = (0.5, 0.5, 0.0)
    goal: Optional[Tuple[float, float]] = None
    name: str = "world"

    # -- building ------------------------------------------------------------
    @classmethod
    def box(cls, width_m: float, height_m: float, name: str = "room") -> World:
        """A rectangular room from (0, 0) to (width_m, height_m), start near a corner.

        Example::

            World.box(4.0, 3.0).walls[0]    # Segment(x1=0.0, y1=0.0, x2=4.0, y2=0.0)
        """
        world = cls(start=(0.5, 0.5, 0.0), name=name)
        world.add_box(0.0, 0.0, width_m, height_m)
        return world

    def add_wall(self, x1: float, y1: float, x2: float, y2: float) -> None:
        """Add one wall from (x1, y1) to (x2, y2).

        Example::

            world.add_wall(2.0, 0.0, 2.0, 1.5)    # a half-height divider
        """
        self.walls.append(Segment(float(x1), float(y1), float(x2), float(y2)))

    def add_box(self, x: float, y: float, width_m: float, height_m: float) -> None:
        """Add the four walls of a rectangle with its lower-left corner at (x, y).

        Example::

            world.add_box(1.5, 1.0, 0.5, 0.5)
        """
        corners = [(x, y), (x + width_m, y), (x + width_m, y + height_m), (x, y + height_m)]
        for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1]):
            self.add_wall(ax, ay, bx, by)

    # -- reading a file ------------------------------------------------------
    @classmethod
    def load(cls, path: Union[str, Path]) -> World:
        """Read a world from a JSON file (the format is in this module's docstring).

        Raises:
            ComponentError: the file is missing, is not JSON, or a wall, box,
                start or goal is not a list of numbers of the right length.

        Example::

            World.load("examples/rover/room.json")
        """
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as error:
            raise ComponentError(
                f"Cannot read the world file {str(path)!r}: {error.strerror or error}. "
                "Check the path (it is relative to the folder you run from)."
            ) from error
        try:
            data = json.loads(text)
        except json.JSONDecodeError as error:
            raise ComponentError(
                f"The world file {str(path)!r} is not valid JSON: {error.msg} at line "
                f"{error.lineno}, column {error.colno}."
            ) from error
        return cls.from_dict(data, where=str(path))

    @classmethod
    def from_dict(cls, data: Any, where: str = "world") -> World:
        """A world from the dict a world file holds (see `load`).

        Example::

            World.from_dict({"walls": [[0, 0, 4, 0]], "start": [1, 1, 0]})
        """
        if not isinstance(data, dict):
            raise ComponentError(
                f"{where}: a world is a JSON object such as "
                '{"walls": [[0, 0, 4, 0], ...], "start": [0.5, 0.5, 0]}, not '
                f"{type(data).__name__}."
            )
        unknown = sorted(set(data) - {"name", "walls", "boxes", "start", "goal"})
        if unknown:
            raise ComponentError(
                f"{where}: unknown field(s) {unknown}; a world has name, walls, boxes, "
                "start and goal."
            )
        world = cls(name=str(data.get("name", Path(where).stem)))
        for i, wall in enumerate(data.get("walls", [])):
            world.add_wall(*_numbers(wall, 4, f"{where}: wall {i}", "[x1, y1, x2, y2]"))
        for i, box in enumerate(data.get("boxes", [])):
            world.add_box(*_numbers(box, 4, f"{where}: box {i}", "[x, y, width, height]"))
        if "start" in data:
            x, y, heading = _numbers(data["start"], 3, f"{where}: start", "[x, y, heading]")
            world.start = (x, y, heading)
        if data.get("goal") is not None:
            gx, gy = _numbers(data["goal"], 2, f"{where}: goal", "[x, y]")
            world.goal = (gx, gy)
        if not world.walls:
            raise ComponentError(
                f'{where}: the world has no walls. Add some under "walls" '
                '([x1, y1, x2, y2] each) or "boxes" ([x, y, width, height] each).'
            )
        return world

    # -- what sensors and collisions ask -------------------------------------
    def ray_hit_m(self, x: float, y: float, heading: float, max_range_m: float) -> float:
        """Distance from (x, y) to the nearest wall along ``heading``, at most ``max_range_m``.

        Example::

            World.box(4, 3).ray_hit_m(1.0, 1.0, 0.0, 10.0)    # 3.0
        """
        dx, dy = math.cos(heading), math.sin(heading)
        nearest = max_range_m
        for wall in self.walls:
            hit = ray_segment_hit_m(x, y, dx, dy, wall)
            if hit is not None and hit < nearest:
                nearest = hit
        return nearest

    def clearance_m(self, x: float, y: float) -> float:
        """Distance from (x, y) to the nearest wall (infinite in an empty world).

        Example::

            World.box(4, 3).clearance_m(1.0, 1.0)    # 1.0
        """
        return min((distance_to_segment_m(x, y, wall) for wall in self.walls), default=math.inf)

    def bounds(self) -> Tuple[float, float, float, float]:
        """(min_x, min_y, max_x, max_y) around every wall: what a picture must show.

        Example::

            World.box(4, 3).bounds()    # (0.0, 0.0, 4.0, 3.0)
        """
        xs = [v for w in self.walls for v in (w.x1, w.x2)] or [0.0, 1.0]
        ys = [v for w in self.walls for v in (w.y1, w.y2)] or [0.0, 1.0]
        return min(xs), min(ys), max(xs), max(ys)


def _numbers(value: Any, count: int, where: str, shape: str) -> Sequence[float]:
    """``value`` as ``count`` floats, or a ComponentError naming where and the shape."""
    if (
        isinstance(value, list)
        and len(value) == count
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        and all(math.isfinite(v) for v in value)
    ):
        return [float(v) for v in value]
    raise ComponentError(f"{where} is {value!r}; write it as {count} numbers, {shape}.")
