"""Drawing the simulated world with pygame: in a window, or into PNG files.

pygame (or pygame-ce, imported as ``pygame`` too) is optional (the ``controller``
extra: ``pip install 'snr-robotics[controller]'``) and imported only when
something is drawn. Nothing here needs a screen:
`render_scene` draws on an off-screen surface, which `save_png` writes out,
so pictures can be made on a robot reached over ssh or in CI (set
``SDL_VIDEODRIVER=dummy`` there if a window is asked for anyway).

What a picture shows: walls in black, the goal as a green ring, the range
rays in red (a lidar's ``scan``: a red dot at each echo), the path taken in
light blue, the robot where it really is (blue, red while bumped, with a
line for its heading) and, as a grey ring, where its odometry thinks it is.

Example::

    pygame = import_pygame()
    surface = render_scene(pygame, WorldView(world), world, pages)
    save_png(pygame, surface, "world.png")
"""

from __future__ import annotations

import collections
import importlib
import math
import os
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Deque, Dict, Iterator, Mapping, Optional, Sequence, Tuple, Union

from snr.extras.controller.keyboard import KeyboardJoystick
from snr.extras.sim.sensors import BUMP, ODOMETRY, RANGE, SCAN, TRUE_POSE
from snr.extras.sim.world import World
from snr.prelude import ComponentError, DataKey
from snr.prelude.install import install_hint

__all__ = [
    "INSTALL_HINT",
    "NO_PICTURES",
    "Scene",
    "WorldView",
    "import_pygame",
    "open_window",
    "pygame_installed",
    "render_scene",
    "save_png",
    "window_closed",
]

INSTALL_HINT = (
    f"Install pygame to see it: `{install_hint('controller')}`, or `pip install pygame` or "
    "`pip install pygame-ce`: either works, both are imported as pygame, and pygame-ce "
    "has wheels for Python 3.14 (on Raspberry Pi OS: `sudo apt install python3-pygame`)"
)
"""How to get pygame, said when the simulator cannot draw."""

NO_PICTURES = f"The simulator runs, but draws nothing: pygame is not installed. {INSTALL_HINT}."
"""What a simulator says, once, when it runs without pygame: no window, no PNG frames."""

Color = Tuple[int, int, int]
BACKGROUND: Color = (250, 250, 245)
WALL: Color = (20, 20, 20)
ROBOT: Color = (40, 90, 200)
BUMPED: Color = (220, 40, 40)
RAY: Color = (235, 120, 120)
ODOMETRY_GHOST: Color = (150, 150, 150)
GOAL: Color = (30, 160, 60)
TRAIL: Color = (120, 150, 220)


def import_pygame() -> ModuleType:
    """pygame, imported now; a `ComponentError` that says how to install it if missing.

    Example::

        pygame = import_pygame()
    """
    # pygame prints a two-line banner on import unless told not to.
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    try:
        return importlib.import_module("pygame")
    except ImportError as error:
        raise ComponentError(
            f"Drawing the simulator needs pygame, which is not installed. {INSTALL_HINT}. "
            "The simulation itself runs without it."
        ) from error


def pygame_installed() -> bool:
    """True if pygame imports, so the simulator can draw: a window or PNG frames.

    A program asks before it promises pictures: without pygame it says
    `NO_PICTURES` instead of naming a folder that will never be made.

    Example::

        if not pygame_installed():
            print(NO_PICTURES)
    """
    try:
        import_pygame()
    except ComponentError:
        return False
    return True


class WorldView:
    """Turns metres in the world into pixels in a picture of it.

    The world's walls fill the picture, less a margin, keeping its shape;
    y grows upwards in the world but downwards on a screen, so it is flipped.

    Example::

        view = WorldView(World.box(4, 3), width_px=640)
        view.size_px                 # (640, 490)
        view.to_px(0.0, 0.0)         # (20, 470): bottom left, inside the margin
    """

    def __init__(self, world: World, width_px: int = 640, margin_px: int = 20) -> None:
        min_x, min_y, max_x, max_y = world.bounds()
        span_x, span_y = max(max_x - min_x, 1e-6), max(max_y - min_y, 1e-6)
        self.scale = (width_px - 2 * margin_px) / span_x  # pixels per metre
        self.origin = (min_x, max_y)  # the world point at the top-left margin
        self.margin_px = margin_px
        self.size_px = (width_px, round(span_y * self.scale) + 2 * margin_px)

    def to_px(self, x: float, y: float) -> Tuple[int, int]:
        """The pixel of the world point (x, y)."""
        return (
            round(self.margin_px + (x - self.origin[0]) * self.scale),
            round(self.margin_px + (self.origin[1] - y) * self.scale),
        )

    def length_px(self, metres: float) -> int:
        """A length in pixels (at least 1)."""
        return max(1, round(metres * self.scale))


def render_scene(
    pygame: Any,
    view: WorldView,
    world: World,
    pages: Mapping[DataKey, Any],
    radius_m: float = 0.1,
    surface: Optional[Any] = None,
    trail: Sequence[Tuple[float, float]] = (),
    trail_px: int = 1,
) -> Any:
    """Draw ``world`` and the robot its ``pages`` describe; returns the surface.

    ``pages`` maps data keys to page data, as `sensor_pages` returns or a
    node's datastore holds (``true_pose``, ``odometry``, ``range``, ``scan``, ``bump``;
    missing keys are simply not drawn). Draws on ``surface`` (a window's)
    or on a new off-screen one. ``trail``: (x, y) points the robot passed,
    drawn as a line ``trail_px`` wide (thin, under a moving robot).

    Example::

        surface = render_scene(pygame, WorldView(world), world, {"true_pose": {...}})
    """
    if surface is None:
        surface = pygame.Surface(view.size_px)
    surface.fill(BACKGROUND)
    for wall in world.walls:
        pygame.draw.line(
            surface, WALL, view.to_px(wall.x1, wall.y1), view.to_px(wall.x2, wall.y2), 3
        )
    if len(trail) >= 2:
        pygame.draw.lines(surface, TRAIL, False, [view.to_px(x, y) for x, y in trail], trail_px)
    if world.goal is not None:
        pygame.draw.circle(surface, GOAL, view.to_px(*world.goal), view.length_px(0.08), 3)
    pose = _pose(pages.get(TRUE_POSE))
    odometry = _pose(pages.get(ODOMETRY))
    if odometry is not None:
        pygame.draw.circle(
            surface,
            ODOMETRY_GHOST,
            view.to_px(odometry[0], odometry[1]),
            view.length_px(radius_m),
            1,
        )
    if pose is not None:
        x, y, theta = pose
        _draw_rays(pygame, surface, view, pose, pages.get(RANGE))
        _draw_echoes(pygame, surface, view, pose, pages.get(SCAN))
        color = BUMPED if pages.get(BUMP) else ROBOT
        centre = view.to_px(x, y)
        pygame.draw.circle(surface, color, centre, view.length_px(radius_m))
        nose = view.to_px(x + radius_m * math.cos(theta), y + radius_m * math.sin(theta))
        pygame.draw.line(surface, BACKGROUND, centre, nose, 2)
    return surface


class Scene:
    """What a view draws each frame: the world, the robot's newest pages and its trail.

    Args:
        pygame: the pygame module.
        world: the walls.
        width_px: the picture's width.
        radius_m: the robot's radius, as drawn.
        trail_points: how many past positions are kept and drawn as its path.
        sensor_keys: the distance sensors' pages it reads: ``range``, ``scan``.

    Example::

        scene = Scene(pygame, world)
        surface = scene.draw(node.get_data)    # reads true_pose, odometry, range, bump
    """

    def __init__(
        self,
        pygame: Any,
        world: World,
        width_px: int = 640,
        radius_m: float = 0.1,
        trail_points: int = 1000,
        sensor_keys: Sequence[DataKey] = (RANGE,),
    ) -> None:
        self.pygame = pygame
        self.keys = (TRUE_POSE, ODOMETRY, *sensor_keys, BUMP)
        self.world = world
        self.view = WorldView(world, width_px)
        self.radius_m = radius_m
        # The path drawn behind the robot: the newest points, a bounded number.
        self.trail: Deque[Tuple[float, float]] = collections.deque(maxlen=max(0, trail_points))

    def draw(self, get_data: Callable[[DataKey], Any], surface: Optional[Any] = None) -> Any:
        """Draw the pages ``get_data`` returns on ``surface`` (or a new one); returns it."""
        pages: Dict[DataKey, Any] = {}
        for key in self.keys:
            data = get_data(key)
            if data is not None:
                pages[key] = data
        pose = pages.get(TRUE_POSE) or pages.get(ODOMETRY)
        if isinstance(pose, dict) and "x" in pose and "y" in pose:
            self.trail.append((pose["x"], pose["y"]))
        return render_scene(
            self.pygame, self.view, self.world, pages, self.radius_m, surface, list(self.trail)
        )


def open_window(pygame: Any, size_px: Tuple[int, int], title: str) -> Any:
    """Open pygame's window (macOS: on the main thread only); returns its surface.

    Example::

        window = open_window(pygame, scene.view.size_px, "SNR simulator")
    """
    pygame.display.init()
    window = pygame.display.set_mode(size_px)
    pygame.display.set_caption(title)
    return window


def window_closed(pygame: Any, keyboard: KeyboardJoystick) -> bool:
    """Read the window's events (on its thread): keys go to ``keyboard``; True once it is closed.

    Reading them also keeps the window alive (answering the system).

    Example::

        if window_closed(pygame, view.keyboard):
            node.schedule(tasks.terminate("simulator window closed"))
    """
    closed = False
    for event in pygame.event.get():
        closed = closed or event.type == pygame.QUIT
        keyboard.handle(event)
    if closed:
        keyboard.release_all()
    return closed


def _ray_ends(
    pose: Tuple[float, float, float], reading: Any
) -> Iterator[Tuple[float, Tuple[float, float]]]:
    """Each ray of a ``range``-shaped page: its distance and where it ends (none if no page)."""
    if not isinstance(reading, dict):
        return
    x, y, theta = pose
    for angle, distance in zip(reading.get("angles_deg", []), reading.get("ranges_m", [])):
        heading = theta + math.radians(angle)
        yield distance, (x + distance * math.cos(heading), y + distance * math.sin(heading))


def _draw_rays(
    pygame: Any, surface: Any, view: WorldView, pose: Tuple[float, float, float], reading: Any
) -> None:
    """A line from the robot to what each range ray sees."""
    for _, end in _ray_ends(pose, reading):
        pygame.draw.line(surface, RAY, view.to_px(pose[0], pose[1]), view.to_px(*end), 1)


def _draw_echoes(
    pygame: Any, surface: Any, view: WorldView, pose: Tuple[float, float, float], scan: Any
) -> None:
    """A dot where each ray of a lidar's scan saw something (0.0: no echo, no dot)."""
    for distance, end in _ray_ends(pose, scan):
        if distance > 0:
            pygame.draw.circle(surface, RAY, view.to_px(*end), 2)


def _pose(data: Any) -> Optional[Tuple[float, float, float]]:
    """(x, y, theta) from a pose page's data, or None if it is not one."""
    if isinstance(data, dict):
        try:
            return float(data["x"]), float(data["y"]), float(data.get("theta", 0.0))
        except (KeyError, TypeError, ValueError):
            return None
    return None


def save_png(pygame: Any, surface: Any, path: Union[str, Path]) -> Path:
    """Write ``surface`` to ``path`` as PNG (folders made as needed); returns the path.

    Example::

        save_png(pygame, surface, "frames/frame_00001.png")
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    pygame.image.save(surface, str(path))
    return path
