"""A procedural building and a simulated LiDAR (deterministic scans)."""

from typing import List, Optional, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

Vec3 = Tuple[float, float, float]

class SensorPose:
    """Where a sensor is and its heading (yaw, radians about +z)."""
    def __init__(self, position: ArrayLike, yaw: float = 0.0) -> None:
        """A sensor at position (3,) metres, heading yaw radians counter-clockwise from +x."""
    @property
    def position(self) -> Vec3:
        """Metres."""
    @property
    def yaw(self) -> float:
        """Heading, radians counter-clockwise from +x."""

class Scene:
    """Solid axis-aligned boxes and vertical cylinders."""
    def __init__(self) -> None:
        """An empty scene."""
    def add_box(self, min: ArrayLike, max: ArrayLike) -> None:
        """Adds a solid box [min, max] (min < max on every axis)."""
    def add_cylinder(self, center_x: float, center_y: float, radius: float, z_min: float, z_max: float) -> None:
        """Adds a solid vertical cylinder."""
    def bounds(self) -> Tuple[Vec3, Vec3]:
        """(min, max) of the smallest box holding every solid."""
    def is_inside_solid(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point (..., 3) lies inside or on a solid: a bool array (...)."""

class LidarModel:
    """A spinning LiDAR: rings x azimuth_steps beams, elevations from fov_down_deg to fov_up_deg, hits within max_range, optional Gaussian range noise (seeded)."""
    def __init__(
        self,
        rings: int = 32,
        fov_down_deg: float = -25.0,
        fov_up_deg: float = 15.0,
        azimuth_steps: int = 720,
        max_range: float = 30.0,
        range_noise_stddev: float = 0.0,
        seed: int = 1,
    ) -> None:
        """The beams and their noise; raises ValueError for a model that cannot scan."""
    @property
    def rings(self) -> int:
        """Beams per azimuth step."""
    @property
    def azimuth_steps(self) -> int:
        """Beams per ring over 360 degrees."""
    @property
    def max_range(self) -> float:
        """Metres; farther hits are not returned."""

def demo_scene() -> Scene:
    """The office floor of the demo: x in [0, 20], y in [0, 12], z in [0, 3], a corridor at y in [5, 7] and six rooms."""

def demo_path() -> List[SensorPose]:
    """Ten SensorPoses at 1.2 m along the demo office's corridor and into a room."""

def simulate_scan(scene: Scene, pose: SensorPose, model: Optional[LidarModel] = None) -> NDArray[np.float32]:
    """End points (N, 3) float32 of one scan from pose, in the map frame (the sensor is at pose.position)."""
