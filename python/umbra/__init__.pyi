"""Type stubs of umbra (the compiled module umbra._umbra, re-exported).

Every docstring here is the runtime one, word for word (python/tests/test_stubs.py
checks). Conventions of every vectorised method: points are arrays (..., 3) and
per-point answers have their leading shape; a batch of shapes takes (N, 3) rows or
one (3,) row for all, (N,) values or one number, and answers (N,).
"""

import os
from typing import Iterator, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import pred as pred
from . import sim as sim

Vec3 = Tuple[float, float, float]
PathLike = Union[str, os.PathLike[str]]
ShapeType = Union["Aabb", "Sphere", "OrientedBox", "Capsule", "Segment"]

__version__: str
UNKNOWN: int
FREE: int
OCCUPIED: int
NODE_DTYPE: np.dtype
GAIN_DTYPE: np.dtype

class FormatError(ValueError):
    """A file that is not what it claims to be; the message names the file and the line or byte offset."""

class Node:
    """One node of a map as a query reports it: a copy that stays valid after the map changes."""
    @property
    def key(self) -> Tuple[int, int, int]:
        """Finest key (x, y, z) of the node's lowest corner voxel."""
    @property
    def depth(self) -> int:
        """0: a voxel; d: a node of 8**d voxels."""
    @property
    def center(self) -> Vec3:
        """Centre (x, y, z) in metres."""
    @property
    def size(self) -> float:
        """Edge length in metres."""
    @property
    def log_odds(self) -> float:
        """Log-odds occupancy: the maximum over the node's voxels."""
    @property
    def occupancy(self) -> float:
        """Occupancy probability of log_odds."""
    @property
    def state(self) -> int:
        """umbra.UNKNOWN, umbra.FREE or umbra.OCCUPIED."""
    @property
    def contains_occupied(self) -> bool:
        """Some voxel in the node is occupied."""
    @property
    def contains_free(self) -> bool:
        """Some voxel in the node is free."""
    @property
    def contains_unknown(self) -> bool:
        """Some voxel in the node is unknown."""
    @property
    def has_children(self) -> bool:
        """The node has children in the map; a childless node's value holds for all its voxels."""
    @property
    def color(self) -> Optional[Tuple[int, int, int]]:
        """The (r, g, b) color of a colored node, else None."""
    @property
    def min_corner(self) -> Vec3:
        """Lowest corner in metres."""
    @property
    def max_corner(self) -> Vec3:
        """Highest corner in metres."""

class SensorModel:
    """Probabilities of the inverse sensor model (OctoMap's defaults). Raises ValueError unless 0.5 < p_hit < 1, 0 < p_miss < 0.5 and 0 < clamp_min <= 0.5 <= clamp_max < 1."""
    def __init__(
        self, p_hit: float = 0.7, p_miss: float = 0.4, clamp_min: float = 0.1192, clamp_max: float = 0.971
    ) -> None:
        """The probabilities; the defaults are OctoMap's."""
    @property
    def p_hit(self) -> float:
        """Probability a hit stands for."""
    @property
    def p_miss(self) -> float:
        """Probability a miss stands for."""
    @property
    def clamp_min(self) -> float:
        """Lowest probability a voxel keeps."""
    @property
    def clamp_max(self) -> float:
        """Highest probability a voxel keeps."""

class Thresholds:
    """Occupied if p > occupied, free if p < free, unknown otherwise. Raises ValueError unless 0 < free <= occupied < 1."""
    def __init__(self, occupied: float = 0.5, free: float = 0.5) -> None:
        """The two thresholds on the occupancy probability; the defaults are OctoMap's."""
    @property
    def occupied(self) -> float:
        """Probability above which a voxel is occupied."""
    @property
    def free(self) -> float:
        """Probability below which a voxel is free."""

class NodeCounts:
    """How many nodes of each kind a map holds."""
    @property
    def inner(self) -> int:
        """Nodes with eight children."""
    @property
    def inner_leaf(self) -> int:
        """Childless nodes above the finest depth."""
    @property
    def leaf(self) -> int:
        """Finest voxels stored."""
    @property
    def total(self) -> int:
        """All nodes."""

class InsertStats:
    """What happened to the points of one scan."""
    @property
    def points(self) -> int:
        """Points given."""
    @property
    def rays(self) -> int:
        """Rays traced (after de-duplication per voxel for discrete / fast)."""
    @property
    def hits(self) -> int:
        """Rays whose end voxel got a hit."""
    @property
    def truncated(self) -> int:
        """Rays beyond max_range, cut there without a hit."""
    @property
    def non_finite(self) -> int:
        """NaN or infinite points, skipped."""
    @property
    def out_of_bounds(self) -> int:
        """Points outside the map, skipped."""
    @property
    def outside_box(self) -> int:
        """Rays missing the bounding box, skipped."""
    @property
    def exclusive_seconds(self) -> float:
        """Seconds the scan kept queries out (its apply phase)."""

class MergeStats:
    """What a merge did."""
    @property
    def voxels(self) -> int:
        """Finest voxels of the map that received a value (a pruned node counts all its voxels)."""
    @property
    def nodes(self) -> int:
        """Node additions applied to the tree (fewer than voxels where pruned blocks land whole)."""

class WindowMove:
    """What one move of the moving window did."""
    @property
    def moved(self) -> bool:
        """False when the box was already there."""
    @property
    def groups_freed(self) -> int:
        """Groups of eight nodes returned to the tree's pools."""
    @property
    def spilled(self) -> bool:
        """Whether a piece was appended to the spill file."""

class MapStatistics:
    """What `umbra info` reports. Voxel counts are in finest voxels; bounds are those of the known space (None when nothing is known)."""
    @property
    def resolution(self) -> float:
        """Edge of a finest voxel, metres."""
    @property
    def depth_levels(self) -> int:
        """Depth levels of the tree."""
    @property
    def nodes(self) -> NodeCounts:
        """Node counts."""
    @property
    def memory_bytes(self) -> int:
        """Bytes allocated for the map."""
    @property
    def occupied_voxels(self) -> int:
        """Occupied finest voxels."""
    @property
    def free_voxels(self) -> int:
        """Free finest voxels."""
    @property
    def occupied_volume_m3(self) -> float:
        """Occupied volume, cubic metres."""
    @property
    def free_volume_m3(self) -> float:
        """Free volume, cubic metres."""
    @property
    def known_min(self) -> Optional[Vec3]:
        """Lowest corner of the known space, or None."""
    @property
    def known_max(self) -> Optional[Vec3]:
        """Highest corner of the known space, or None."""

class Aabb:
    """An axis-aligned box [min, max] in metres. ValueError unless min <= max, finite."""
    def __init__(self, min: ArrayLike, max: ArrayLike) -> None:
        """The box from corner min (3,) to corner max (3,)."""
    @property
    def min(self) -> Vec3:
        """Lowest corner."""
    @property
    def max(self) -> Vec3:
        """Highest corner."""

class OrientedBox:
    """A box turned in space: centre, half edge lengths along its own axes, and a rotation matrix whose columns are those axes in map coordinates (orthonormal; identity when None)."""
    def __init__(self, center: ArrayLike, half_extents: ArrayLike, rotation: Optional[ArrayLike] = None) -> None:
        """The box of half edge lengths half_extents (3,) about center (3,), turned by rotation (3, 3) (None: not turned)."""
    @staticmethod
    def from_yaw_pitch_roll(
        center: ArrayLike, half_extents: ArrayLike, yaw: float, pitch: float = 0.0, roll: float = 0.0
    ) -> OrientedBox:
        """The box's x axis along (cos p cos y, cos p sin y, sin p), y and z turned by roll about it (radians)."""
    @staticmethod
    def from_quaternion(center: ArrayLike, half_extents: ArrayLike, quaternion: ArrayLike) -> OrientedBox:
        """The box turned by the quaternion (w, x, y, z), normalised first."""
    @property
    def center(self) -> Vec3:
        """Centre."""
    @property
    def half_extents(self) -> Vec3:
        """Half edge lengths along the box's axes."""
    @property
    def rotation(self) -> NDArray[np.float64]:
        """3x3 matrix whose columns are the box's axes."""

class Sphere:
    """A ball: centre and radius (>= 0) in metres."""
    def __init__(self, center: ArrayLike, radius: float) -> None:
        """The ball of radius about center (3,)."""
    @property
    def center(self) -> Vec3:
        """Centre."""
    @property
    def radius(self) -> float:
        """Radius."""

class Capsule:
    """The points within radius of the segment from a to b."""
    def __init__(self, a: ArrayLike, b: ArrayLike, radius: float) -> None:
        """The points within radius of the segment from a (3,) to b (3,)."""
    @property
    def a(self) -> Vec3:
        """One end of the axis."""
    @property
    def b(self) -> Vec3:
        """The other end."""
    @property
    def radius(self) -> float:
        """Radius."""

class Segment:
    """A line segment; in checks, the voxels of its ray walk from start (OctoMap's computeRayKeys) plus the voxel of end."""
    def __init__(self, start: ArrayLike, end: ArrayLike) -> None:
        """The segment from start (3,) to end (3,)."""
    @property
    def start(self) -> Vec3:
        """First point."""
    @property
    def end(self) -> Vec3:
        """Last point."""

class Frustum:
    """A sensor's field of view from origin, looking along (cos p cos y, cos p sin y, sin p); angles in radians, full fields of view in (0, pi), min_range <= |d| <= max_range."""
    def __init__(
        self, origin: ArrayLike, yaw: float, pitch: float, hfov: float, vfov: float, min_range: float, max_range: float
    ) -> None:
        """The field of view from origin (3,), angles in radians (from_degrees takes degrees)."""
    @staticmethod
    def from_degrees(
        origin: ArrayLike, yaw: float, pitch: float, hfov: float, vfov: float, min_range: float, max_range: float
    ) -> Frustum:
        """The same with the four angles in degrees."""
    @property
    def origin(self) -> Vec3:
        """Sensor position."""
    @property
    def yaw(self) -> float:
        """Heading, radians."""
    @property
    def pitch(self) -> float:
        """Elevation, radians (positive looks up)."""
    @property
    def hfov(self) -> float:
        """Full horizontal field of view, radians."""
    @property
    def vfov(self) -> float:
        """Full vertical field of view, radians."""
    @property
    def min_range(self) -> float:
        """Nearest distance seen."""
    @property
    def max_range(self) -> float:
        """Farthest distance seen."""
    def contains(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point (..., 3) lies in the frustum: a bool array (...)."""

class GainResult:
    """The information gain of one sensor pose."""
    @property
    def unknown_voxels(self) -> int:
        """Unknown finest voxels whose centre lies in the frustum and is visible from its origin."""
    @property
    def volume(self) -> float:
        """Their volume, cubic metres."""
    @property
    def entropy_bits(self) -> float:
        """Sum of the binary entropy of their occupancy, bits (unknown_voxels with the default thresholds)."""

class NavigationGrid:
    """A map projected between two heights (OccupancyMap.project): a 2D grid of cells."""
    @property
    def cells(self) -> NDArray[np.int8]:
        """The cells, an int8 array (height, width): -1 unknown, 0 free, 100 occupied; cells[j, i] is column i (x) of row j (y), row 0 the lowest y (nav_msgs/OccupancyGrid's layout). Read-only."""
    @property
    def resolution(self) -> float:
        """Edge of a cell, metres."""
    @property
    def depth(self) -> int:
        """The map depth whose node columns are the cells."""
    @property
    def origin(self) -> Tuple[float, float]:
        """(x, y) of the lower-left corner of cell [0, 0], metres."""
    @property
    def width(self) -> int:
        """Cells along x."""
    @property
    def height(self) -> int:
        """Cells along y."""
    def save(self, path: PathLike) -> str:
        """Writes map_server's PGM picture to path (.pgm) and its YAML description beside it (.yaml), both atomically; returns the YAML file's path. ValueError for an empty grid or a path not ending in .pgm, OSError when a file cannot be written."""

class Predicate:
    """Which nodes a query wants; made by the functions of umbra.pred and combined with & (and), | (or) and ~ (not)."""
    def __and__(self, other: Predicate) -> Predicate: ...
    def __or__(self, other: Predicate) -> Predicate: ...
    def __invert__(self) -> Predicate: ...
    def __bool__(self) -> bool: ...

class CollisionResult:
    """The answer of is_free: free, and when not free one blocking node (for a segment the first along it). True when free."""
    @property
    def free(self) -> bool:
        """No voxel of the shape blocks."""
    @property
    def blocking(self) -> Optional[Node]:
        """A blocking Node, or None when free."""
    def __bool__(self) -> bool: ...

class RayHit:
    """The answer of cast_ray. True when something was hit."""
    @property
    def hit(self) -> bool:
        """An occupied (or, when asked, unknown) node was hit within range."""
    @property
    def node(self) -> Optional[Node]:
        """The Node hit, or None."""
    @property
    def distance(self) -> float:
        """Metres from the origin to where the ray enters the node."""
    @property
    def point(self) -> Vec3:
        """origin + direction * distance."""
    def __bool__(self) -> bool: ...

class RayHits:
    """The answers of cast_rays, one row per ray."""
    @property
    def hit(self) -> NDArray[np.bool_]:
        """(N,) bool: something was hit within range."""
    @property
    def distance(self) -> NDArray[np.float64]:
        """(N,) metres to where the ray enters the node hit, or NaN."""
    @property
    def point(self) -> NDArray[np.float64]:
        """(N, 3) origin + direction * distance, or NaN."""
    @property
    def center(self) -> NDArray[np.float64]:
        """(N, 3) centre of the node hit, or NaN."""
    @property
    def size(self) -> NDArray[np.float64]:
        """(N,) edge of the node hit, or NaN."""
    def __len__(self) -> int: ...

class OccupancyMap:
    """A probabilistic occupancy octree with unknown, free and occupied space explicit. Every method may be called from any thread; queries run while another thread inserts."""
    def __init__(
        self,
        resolution: float,
        depth_levels: int = 16,
        color: bool = False,
        sensor_model: Optional[SensorModel] = None,
        thresholds: Optional[Thresholds] = None,
    ) -> None:
        """An empty map, everything unknown: finest voxels of resolution metres, depth_levels levels (1..21; the map spans [-resolution * 2**(depth_levels - 1), resolution * 2**(depth_levels - 1)) on every axis), a color per voxel when color, and a SensorModel and Thresholds (None: OctoMap's defaults)."""
    @property
    def resolution(self) -> float:
        """Edge of a finest voxel, metres."""
    @property
    def depth_levels(self) -> int:
        """Depth levels of the tree (1..21)."""
    @property
    def half_extent(self) -> float:
        """The map spans [-half_extent, half_extent) metres on every axis."""
    @property
    def has_color(self) -> bool:
        """Whether the map keeps a color per voxel."""
    @property
    def sensor_model(self) -> SensorModel:
        """The SensorModel of future updates; setting it clamps stored values into its range."""
    @sensor_model.setter
    def sensor_model(self, value: SensorModel) -> None: ...
    @property
    def thresholds(self) -> Thresholds:
        """The Thresholds of the states; setting them updates every indicator at once."""
    @thresholds.setter
    def thresholds(self, value: Thresholds) -> None: ...
    @property
    def auto_prune(self) -> bool:
        """Merge eight equal children into their parent (default True; setting it prunes the map)."""
    @auto_prune.setter
    def auto_prune(self, value: bool) -> None: ...
    @property
    def bounding_box(self) -> Optional[Aabb]:
        """An Aabb limiting future insertions (rays clipped to it), or None."""
    @bounding_box.setter
    def bounding_box(self, value: Optional[Aabb]) -> None: ...
    # --- decay toward unknown
    def set_decay(self, occupied_per_second: float, free_per_second: float, region: Optional[Aabb] = None) -> None:
        """From now on every advance of the clock moves each voxel (in region, an Aabb, if given) toward unknown (log-odds 0) by rate x seconds passed: occupied_per_second off occupied values, free_per_second off free ones; both 0: no decay. ValueError for a negative or non-finite rate."""
    @property
    def decay(self) -> Tuple[float, float, Optional[Aabb]]:
        """The decay rates as (occupied_per_second, free_per_second, region or None)."""
    def advance_clock(self, time: float) -> None:
        """Advances the map's clock to time (seconds) and decays the map by the time passed; the first time only sets the clock, an earlier time changes nothing."""
    @property
    def clock(self) -> Optional[float]:
        """The clock's time in seconds, or None before the first advance_clock or stamp."""
    def prune(self) -> None:
        """Merge equal children now."""
    def clear(self) -> None:
        """Make everything unknown again."""
    def node_counts(self) -> NodeCounts:
        """How many nodes of each kind the map holds (a NodeCounts)."""
    def memory_bytes(self) -> int:
        """Bytes allocated for the map."""
    def statistics(self) -> MapStatistics:
        """Voxel counts, volumes and bounds of the known space (a MapStatistics; one pass over the leaves)."""
    def copy(self) -> OccupancyMap:
        """A deep copy."""
    def __copy__(self) -> OccupancyMap: ...
    def __deepcopy__(self, memo: object) -> OccupancyMap: ...
    def save(self, path: PathLike) -> None:
        """Saves the map as .umb, .bt or .ot (by extension), atomically: a temporary file renamed over path."""

    # --- merging maps
    def merge(
        self,
        other: OccupancyMap,
        offset: Optional[Sequence[int]] = None,
        transform: Optional[ArrayLike] = None,
    ) -> MergeStats:
        """Adds other's log-odds to this map's, voxel by voxel, clamped to this map's sensor model; voxels other never observed change nothing. offset (3 ints): other's voxel k lands on k + offset. transform ((4, 4) or (3, 4), other's frame to this map's, rigid): each voxel takes other's voxel its centre maps back into. Colors average by their sample counts where both maps have color. ValueError for other resolutions or depth levels, a transform that is not rigid, or both offset and transform; IndexError when a known voxel of other lands outside this map (the map is unchanged then). Returns MergeStats."""

    # --- a map that moves
    def set_moving_window(
        self,
        half_extent: Optional[float],
        spill_path: Optional[PathLike] = None,
        step_depth: int = -1,
        follow_scans: bool = True,
    ) -> None:
        """Keeps only a box around the robot: every point within half_extent metres of it on each axis, in whole nodes of depth step_depth (-1: automatic). With follow_scans every insert first re-centres the box on its origin, and scans change only the box. What leaves the box is appended to spill_path (a spill file, see load_spill) or dropped, then forgotten (unknown, memory freed). None: no window (the map keeps what it holds). ValueError for a bad half_extent or step_depth."""
    def move_window(self, position: ArrayLike) -> WindowMove:
        """Re-centres the moving window's box on position (the robot); what leaves goes to the spill file or is dropped. RuntimeError without a window, IndexError outside the map. Returns a WindowMove."""
    @property
    def window_box(self) -> Optional[Tuple[Tuple[int, int, int], Tuple[int, int, int]]]:
        """The moving window's box as ((lo keys), (hi keys)), inclusive; None before it is placed."""

    # --- inserting and changing voxels
    def insert(
        self,
        points: ArrayLike,
        origin: ArrayLike,
        colors: Optional[ArrayLike] = None,
        *,
        integrator: str = "discrete",
        max_range: float = -1.0,
        clear_depth: int = -1,
        fine_steps: int = 2,
        threads: int = 0,
        stamp: Optional[float] = None,
    ) -> InsertStats:
        """Integrates one scan: points (N, 3) seen from origin (3,), optionally colors (N, 3) uint8. Returns InsertStats. integrator: 'discrete' (OctoMap's discretize=true), 'simple' (discretize=false) or 'fast' (free space cleared at clear_depth, -1: 16 cm nodes; fine_steps coarse nodes before each end point traced voxel by voxel). max_range <= 0: unlimited. threads: 0 for all cores. stamp: seconds on the map's clock, advanced to it first (decay, see set_decay); None: the clock is left alone."""
    def insert_depth_image(
        self,
        depth: ArrayLike,
        camera: Union[PinholeCamera, Sequence[float]],
        pose: ArrayLike,
        colors: Optional[ArrayLike] = None,
        *,
        depth_scale: Optional[float] = None,
        integrator: str = "projective",
        max_range: float = -1.0,
        surface_margin: float = 0.0,
        clear_depth: int = -1,
        fine_steps: int = 2,
        threads: int = 0,
    ) -> InsertStats:
        """Integrates one depth image taken from pose: depth (H, W) uint16 raw units (depth_scale units per metre, e.g. 1000 for millimetres) or float metres (0, negative, NaN or infinite: no reading); camera a PinholeCamera or (fx, fy, cx, cy); pose (4, 4) or (3, 4) camera-to-map, a rotation and a translation (the optical frame: x right, y down, z forward); colors (H, W, 3) uint8, one per pixel (the map needs color). Returns InsertStats. integrator 'projective': free space from the image itself, a voxel cleared when it lies more than surface_margin voxels in front of the reading it projects onto, hits from the image's points as 'discrete' gives them; any other integrator inserts back_project's points from the camera's position as insert() does. max_range <= 0: unlimited. threads: 0 for all cores."""
    def update_hit(self, points: ArrayLike) -> None:
        """One hit for the voxel of each point (..., 3)."""
    def update_miss(self, points: ArrayLike) -> None:
        """One miss for the voxel of each point (..., 3)."""
    def update_log_odds(self, points: ArrayLike, deltas: ArrayLike) -> None:
        """Adds deltas (N,) or one number to the voxels' log-odds, then clamps."""
    def set_log_odds(self, points: ArrayLike, values: ArrayLike) -> None:
        """Sets the voxels' log-odds (clamped) to values (N,) or one number."""
    def add_color(self, points: ArrayLike, colors: ArrayLike) -> None:
        """One more color sample (N, 3) uint8 for the voxel of each point (running average)."""

    # --- reading the nodes that hold points
    def states(self, points: ArrayLike, depth: int = 0) -> NDArray[np.uint8]:
        """State of the depth-`depth` node holding each point (..., 3): a uint8 array (...) of umbra.UNKNOWN, FREE, OCCUPIED."""
    def log_odds(self, points: ArrayLike, depth: int = 0) -> NDArray[np.float32]:
        """Log-odds of the node holding each point (the maximum over its voxels): a float32 array (...)."""
    def occupancy(self, points: ArrayLike, depth: int = 0) -> NDArray[np.float64]:
        """Occupancy probability of the node holding each point: a float64 array (...)."""
    def nodes(self, points: ArrayLike, depth: int = 0) -> NDArray[np.void]:
        """The depth-`depth` node holding each point (or the childless node above it): a structured array (...) of umbra.NODE_DTYPE."""
    def leaves(self) -> NDArray[np.void]:
        """Every childless node in Morton order: a structured array of umbra.NODE_DTYPE."""

    # --- queries
    def query(self, predicate: Optional[Predicate] = None, depth: int = 0) -> NDArray[np.void]:
        """The nodes the predicate holds for (None: all), visiting the tree down to `depth`, parents before children in Morton order: a structured array of umbra.NODE_DTYPE."""
    def query_nearest(
        self,
        point: ArrayLike,
        predicate: Optional[Predicate] = None,
        depth: int = 0,
        max_distance: float = ...,
        k: Optional[int] = None,
    ) -> Tuple[NDArray[np.void], NDArray[np.float64]]:
        """The matching nodes nearest to point first, up to max_distance metres and at most k of them: (nodes, distances), a structured array of umbra.NODE_DTYPE and the float64 distances to the nodes' cubes (0 inside)."""
    def count(self, predicate: Optional[Predicate] = None, depth: int = 0) -> int:
        """How many nodes query(predicate, depth) yields."""

    # --- collision checks
    def is_free(self, shape: ShapeType, *, unknown_is_free: bool = False, depth: int = 0) -> CollisionResult:
        """Whether no voxel of the shape (an Aabb, Sphere, OrientedBox, Capsule or Segment) blocks: occupied, or unknown unless unknown_is_free; checked at `depth` (coarser is conservative). Returns a CollisionResult (true when free) with one blocking node."""
    def spheres_free(
        self, centers: ArrayLike, radii: ArrayLike, *, unknown_is_free: bool = False, depth: int = 0
    ) -> NDArray[np.bool_]:
        """Whether each sphere is free: centers (N, 3), radii (N,) or one radius. A bool array (N,)."""
    def boxes_free(
        self, mins: ArrayLike, maxs: ArrayLike, *, unknown_is_free: bool = False, depth: int = 0
    ) -> NDArray[np.bool_]:
        """Whether each axis-aligned box [mins[i], maxs[i]] is free: a bool array (N,)."""
    def oriented_boxes_free(
        self,
        centers: ArrayLike,
        half_extents: ArrayLike,
        rotations: ArrayLike,
        *,
        unknown_is_free: bool = False,
        depth: int = 0,
    ) -> NDArray[np.bool_]:
        """Whether each oriented box is free: centers (N, 3), half_extents (N, 3), rotations (N, 3, 3) whose columns are the boxes' axes (each may be one row for all). A bool array (N,)."""
    def capsules_free(
        self,
        starts: ArrayLike,
        ends: ArrayLike,
        radii: ArrayLike,
        *,
        unknown_is_free: bool = False,
        depth: int = 0,
    ) -> NDArray[np.bool_]:
        """Whether each capsule (the points within radii[i] of the segment starts[i] -> ends[i]) is free: a bool array (N,)."""
    def segments_free(
        self, starts: ArrayLike, ends: ArrayLike, *, unknown_is_free: bool = False, depth: int = 0
    ) -> NDArray[np.bool_]:
        """Whether each segment's ray walk (OctoMap's computeRayKeys plus the end voxel) is free: a bool array (N,)."""

    # --- ray casts
    def cast_ray(
        self,
        origin: ArrayLike,
        direction: ArrayLike,
        *,
        max_range: float = -1.0,
        stop_at_unknown: bool = False,
        depth: int = 0,
    ) -> RayHit:
        """The first occupied (or, with stop_at_unknown, unknown) node along the ray within max_range (<= 0: to the map's edge): a RayHit."""
    def cast_rays(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        *,
        max_range: ArrayLike = -1.0,
        stop_at_unknown: bool = False,
        depth: int = 0,
    ) -> RayHits:
        """cast_ray for many rays: origins and directions (N, 3) or one row each, max_range (N,) or one number. Returns RayHits: hit (N,) bool, and distance, point (N, 3), center (N, 3) and size of the node hit (NaN where nothing was hit)."""
    def cast_rays_octomap(
        self, origins: ArrayLike, directions: ArrayLike, *, ignore_unknown: bool = False, max_range: float = -1.0
    ) -> Tuple[NDArray[np.bool_], NDArray[np.float32]]:
        """OctoMap's OcTree::castRay rule for rule, for many rays (float32, as OctoMap): (hit (N,) bool, end (N, 3) float32), end being the centre of the voxel hit or where the ray stopped."""

    # --- information gain
    def information_gain(self, frustum: Frustum, *, method: str = "exact", fast_depth: int = 2) -> GainResult:
        """The unknown finest voxels a sensor with this Frustum would see (centre in the frustum, no occupied voxel on the ray from its origin): a GainResult. method 'exact' counts them voxel by voxel; 'fast' decides nodes of up to 2^fast_depth voxels per edge by their corner voxels."""
    @overload
    def information_gains(
        self, frustums: Sequence[Frustum], *, method: str = "exact", fast_depth: int = 2, threads: int = 0
    ) -> NDArray[np.void]: ...
    @overload
    def information_gains(
        self,
        origins: ArrayLike,
        yaw: ArrayLike,
        pitch: ArrayLike,
        hfov: ArrayLike,
        vfov: ArrayLike,
        min_range: ArrayLike,
        max_range: ArrayLike,
        *,
        method: str = "exact",
        fast_depth: int = 2,
        threads: int = 0,
    ) -> NDArray[np.void]:
        """information_gain of many poses: a list of Frustums, or origins (N, 3), yaw and pitch (N,) in degrees and hfov, vfov (degrees), min_range, max_range, each (N,) or one number for all. Returns a structured array (N,) of umbra.GAIN_DTYPE (unknown_voxels, volume, entropy_bits). threads: 0 for all cores. A bad pose raises ValueError (IndexError for an origin outside the map) naming its index."""

    # --- the navigation grid
    def project(self, z_min: float, z_max: float, *, depth: int = 0, rule: str = "all_known") -> NavigationGrid:
        """The map projected between heights z_min and z_max (metres): a NavigationGrid. A cell (the column of a depth-`depth` node) is occupied if a voxel of its band (the voxel rows from the one holding z_min to the one holding z_max) is occupied; free if every voxel of the band is free (rule 'all_known') or if at least one is (rule 'any_free', octomap_server's); unknown otherwise. The grid spans the cells whose band holds a known voxel (empty when none does). ValueError for z_min >= z_max, a bad depth or rule; IndexError when the band lies outside the map."""

def load_spill(path: PathLike) -> OccupancyMap:
    """Every piece of a moving window's spill file merged into one map (log-odds added); merge the window's map into it to get the whole run. FormatError naming the byte offset for a damaged file."""

def load(path: PathLike, sensor_model: Optional[SensorModel] = None) -> OccupancyMap:
    """Loads a map from a .umb, .bt or .ot file (by extension). sensor_model applies to OctoMap files only (they store none)."""

class DistanceField:
    """Distances from any point to the nearest occupied and the nearest unknown voxel of a map, capped at max_distance, with the gradient; kept up to date by update() after scans."""

    def __init__(
        self,
        map: OccupancyMap,
        *,
        max_distance: float = 1.0,
        depth: int = 0,
        box: Optional[Aabb] = None,
        threads: int = 1,
    ) -> None:
        """Builds the field of `map` (kept alive by the field): cells of depth `depth`, distances capped at max_distance metres, inside `box` (an Aabb) or, without one, over the whole known space; built and updated by `threads` threads (0: all)."""
    def update(self) -> None:
        """Brings the field up to date with the map, recomputing only near what changed since the last update."""
    def rebuild(self) -> None:
        """Recomputes everything."""
    def set_box(self, box: Optional[Aabb]) -> None:
        """Moves the box (an Aabb, or None: the whole known space) and rebuilds."""
    @property
    def max_distance(self) -> float:
        """Metres; distances are capped here."""
    @property
    def depth(self) -> int:
        """Depth of the cells (0: finest voxels)."""
    def memory_bytes(self) -> int:
        """Bytes the field holds."""
    def distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Distance to the nearest blocking (occupied or unknown) voxel of each point (..., 3): an array (...). A point outside the map (or the box) raises IndexError naming its index."""
    def distance_and_gradient(self, points: ArrayLike) -> NDArray[np.float64]:
        """For each point (..., 3) the row (d_occupied, d_unknown, gx, gy, gz): metres to the nearest occupied and unknown voxel (capped at max_distance) and the unit vector away from the nearest blocking one: an array (..., 5)."""

class DepthCamera:
    """A pinhole depth camera: pixel (u, v) with raw depth d lies at z = d / depth_scale metres, x = (u - cx) z / fx, y = (v - cy) z / fy. Defaults: the TUM fr2 Kinect."""
    def __init__(
        self, fx: float = 580.8, fy: float = 581.8, cx: float = 308.8, cy: float = 253.0, depth_scale: float = 5000.0
    ) -> None:
        """The intrinsics in pixels and raw units per metre."""
    @property
    def fx(self) -> float:
        """Focal length along u, pixels."""
    @property
    def fy(self) -> float:
        """Focal length along v, pixels."""
    @property
    def cx(self) -> float:
        """Principal point u, pixels."""
    @property
    def cy(self) -> float:
        """Principal point v, pixels."""
    @property
    def depth_scale(self) -> float:
        """Raw depth units per metre."""

class PinholeCamera:
    """Pinhole intrinsics in pixels: pixel (u, v) (from 0 at the top-left pixel's centre) with depth z lies at x = (u - cx) z / fx, y = (v - cy) z / fy in the optical frame (x right, y down, z forward)."""
    def __init__(self, fx: float, fy: float, cx: float, cy: float) -> None:
        """Focal lengths fx, fy and principal point cx, cy, pixels (focal lengths > 0, all finite)."""
    @property
    def fx(self) -> float:
        """Focal length along u, pixels."""
    @property
    def fy(self) -> float:
        """Focal length along v, pixels."""
    @property
    def cx(self) -> float:
        """Principal point u, pixels."""
    @property
    def cy(self) -> float:
        """Principal point v, pixels."""
    def __eq__(self, other: object) -> bool: ...

@overload
def back_project(
    depth: ArrayLike,
    camera: Union[PinholeCamera, Sequence[float]],
    pose: Optional[ArrayLike] = None,
    *,
    depth_scale: Optional[float] = None,
    return_pixels: Literal[False] = False,
) -> NDArray[np.float32]: ...
@overload
def back_project(
    depth: ArrayLike,
    camera: Union[PinholeCamera, Sequence[float]],
    pose: Optional[ArrayLike] = None,
    *,
    depth_scale: Optional[float] = None,
    return_pixels: Literal[True],
) -> Tuple[NDArray[np.float32], NDArray[np.uint32]]:
    """The points (N, 3) float32 of the pixels of a depth image that have a reading, row by row: depth (H, W) uint16 raw units (depth_scale units per metre) or float metres (0, negative, NaN or infinite: no reading); camera a PinholeCamera or (fx, fy, cx, cy); pose (4, 4) or (3, 4) camera-to-map, None for the camera frame. With return_pixels, (points, pixels): each point's pixel index v * W + u, (N,) uint32. insert_depth_image inserts these very points."""

Scan = Tuple[NDArray[np.float32], NDArray[np.float32], Optional[NDArray[np.uint8]]]

class ScanReader:
    """An iterator of scans (origin (3,) float32, points (N, 3) float32, colors (N, 3) uint8 or None), read one at a time."""
    def __iter__(self) -> Iterator[Scan]: ...
    def __next__(self) -> Scan: ...
    @property
    def scan_count(self) -> int:
        """Number of scans when the format says so up front, else 0."""
    @property
    def progress(self) -> float:
        """Fraction of the input read, 0..1."""
    @property
    def name(self) -> str:
        """Where the last scan came from, e.g. 'run.graph scan 3'."""
    @property
    def stamp(self) -> Optional[float]:
        """The last scan's time in seconds where the input states it (TUM: the depth image's name; ROS bags: header.stamp), else None: pass it to Map.insert(stamp=...) for decay."""

def read_scans(
    path: PathLike,
    format: Optional[str] = None,
    *,
    origin: ArrayLike = (0.0, 0.0, 0.0),
    poses: Optional[PathLike] = None,
    calibration: Optional[PathLike] = None,
    association: Optional[PathLike] = None,
    camera: Optional[DepthCamera] = None,
) -> ScanReader:
    """Reads the scans of a point-cloud file or folder: a ScanReader. format: 'graph', 'xyz', 'ply', 'pcd', 'kitti' or 'tum' (None: by name). origin: the sensor for formats without a pose; poses, calibration: KITTI; association, camera (a DepthCamera): TUM RGB-D."""
