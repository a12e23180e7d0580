// ProjectiveFrame: one depth image as the projective integrator reads it,
// and the rule that decides which voxels it clears.
//
// The rule (docs/design.md, "The projective integrator"), per finest voxel v
// with camera-frame centre p = (x, y, z), projected to u = fx x / z + cx +
// 1/2, v = fy y / z + cy + 1/2 (pixel (i, j) covers [i, i + 1) x [j, j + 1)):
//  - the *window* of v is the part of the image a ray through v may come
//    from: v's own pixel when v is smaller than a pixel there, else the
//    2 x 2 cells of a pyramid level (cells of 2^l pixels) nearest to (u, v),
//    with 2^l about the width v projects to (below);
//  - v is *seen* when z > 0, v is within range (below) and its window
//    holds a reading;
//  - v is *cleared* (gets a miss) when it is seen and some pixel of its
//    window has a reading d with z < d - margin, and every voxel of its
//    *seen unit* is seen: its brick (the 4 x 4 x 4 voxels of its depth-2
//    node) at resolutions of 5 mm and finer, its group of eight (its
//    depth-1 node) in depth images at 6 mm to 2 cm, v itself otherwise.
// In words: some pixel whose ray passes through the voxel saw a surface
// beyond it, which is when OctoMap's ray from that pixel would clear it.
// Taking the voxel's own pixel only (the centre ray) left 5% of the simple
// integrator's free voxels unknown on the TUM frames at 4 cm and lost 1.2%
// precision (stale obstacles a neighbouring ray would have cleared); the
// window brings that to 1.2% and 0.4% (docs/benchmarks.md). Pixels without
// a reading clear nothing: a voxel whose window holds none stays as it was.
//
// At the image's edges: a voxel whose centre projects outside the image by
// less than its half width w (below) reads the nearest pixel or window
// inside, as the rays of the edge pixels cross it (the simulated camera at
// 2 cm: 1.9% of the simple integrator's free voxels left unknown without
// this, 1.5% with it; occupied recall and precision unchanged).
//
// Seen units. Free space ends where the image stops seeing: at the
// image's edges and around pixels without readings, whose cones run from
// the camera to the surface. Voxel by voxel those borders cost the map a
// leaf group per few voxels of their area: at 4 mm the ten TUM frames' map
// held 75 million nodes (794 MiB with color), three times the map with
// whole bricks. So at 5 mm and finer a brick (2 cm and less) is seen whole
// or not at all. At 2 cm (depth images) a group of eight (4 cm) is: the
// ten TUM frames' tree went from 2.08 M nodes (10.2 MiB) to 1.32 M (7.1
// MiB; the fast integrator's 1.42 M, 6.9 MiB), the simple integrator's
// free voxels left unknown from 1.24% to 3.0% (bricks of 8 cm: 7%). At 4
// and 5 cm groups left 4.0% and 4.98% unknown on the same frames, too near
// the 5% the rule is held to, and on the 3DTK scans at 2 cm 4.8% (1.5%
// voxel by voxel; their rays are sparse): there the borders stay exact
// (docs/benchmarks.md, "Round nine (issue 22)"). A whole seen unit is all
// the rule adds: a voxel cleared was seen (d > margin >= 0), so the walk's
// whole-node decisions (every voxel cleared, or none) stay the rule's.
//
// The window level is chosen per brick (the 4 x 4 x 4 voxels of a depth-2
// node, the unit the rule is evaluated in): from the camera-frame depth
// z_ref of the brick's centre, w = (min(fx, fy) resolution / 2) / z_ref is half the
// width a voxel projects to, in pixels; l = 0 when w < 1 (the voxel's own
// pixel), else l = bit_width(floor(w)), at most the pyramid's top level
// (also when z_ref <= 0). The 2 x 2 cells of level l nearest to (u, v) are
// those from floor(u / 2^l - 1/2) and floor(v / 2^l - 1/2); cells outside the
// level hold no reading. At level 0 the pixel must lie in the image.
//
// Known obstacles (images of scans: scan_images.hpp). A voxel the map holds
// as occupied (before this scan) is cleared only when one of the image's
// rays really passes through it and ends beyond it (a segment-cube test in double against the rays of the
// 3 x 3 pixels in the middle of those its cube projects onto), as OctoMap's
// ray would clear it: the
// rule's view of free space is the whole cone of a pixel in front of its
// reading, and a surface seen at a grazing angle from elsewhere can lie in
// that cone while no ray of this scan crosses it. (The fast integrator
// never clears known obstacles wholesale either.) Without this, a LiDAR
// scan binned at its ring spacing cleared 3% of the floor the simple
// integrator keeps. Depth images need no such test: their rays are as dense
// as their pixels, so the cone of a pixel is its ray's neighbourhood (on the
// TUM frames the test changed recall and precision by 0.1% to 0.3% either
// way and cost half the misses' time).
//
// Several readings a pixel. The images of a LiDAR scan (scan_images.hpp)
// can hold several points in a pixel, and keep the nearest of each half
// pixel too (depth_halves): at level 0 a voxel reads its half pixel's
// nearest where that has a point, else its pixel's nearest. The space a ray
// passing beside a nearer point reaches is then cleared in half the pixels
// it would be lost in (on the 3DTK scans at 5 cm the simple integrator's
// free voxels left unknown went from 6.1% to 4.4%). The pyramid's maxima
// come from the halves (their nearest readings), so the windows of larger
// voxels see them too.
//
// Cells where voxels are narrower than pixels. At 5 mm and finer, and for
// depth images (not the images of scans), a node of depth 2 + c (c >= 1)
// whose depth-c nodes each project onto less than four pixels (the node
// read as one brick of the grid of 2^c times the resolution has window
// level 0 or 1) and are at most 1 cm wide is decided by *cells* of level c:
// the rule above
// evaluated on that coarser grid, whose voxels are the depth-c nodes; a
// cleared cell clears all its voxels. The coarsest level that applies is
// taken (the walk meets it first). The cells use the finest grid's edge
// reach, margin (in metres) and range test (per depth-range_depth node,
// which must hold the node: else no cells), so that the walk's whole-node
// decisions, made for the finest voxels, hold for the cells too. Why: there
// the image cannot tell a cell's voxels apart (they read the same pixel or
// its neighbour), and the noise of a depth camera (1 to 5 cm at 2 to 4 m,
// 5 to 25 voxels at 2 mm) makes a band in front of every surface where the
// answer changes voxel by voxel: ten TUM frames at 2 mm visited 5.5 million
// bricks a frame and stored 113 million nodes. The hits stay the finest
// voxels'. (Cells up to two pixels wide: 1.2x to 1.3x slower at 4 and 2
// mm, the maps 2% to 4% larger; the simple integrator's free voxels left
// unknown went from 2.8% to 2.7% at 4 mm and 1.7% to 2.0% at 2 mm, TUM in
// a box, recall and precision >= 99.93% either way.)
//
// Range. With max_range set, v is within range when every voxel centre of
// its depth-`range_depth` ancestor is within max_range of the camera (a test
// in double), range_depth being the depth whose nodes are closest to
// max_range / 64. Free space thus ends at max_range in steps of those nodes
// rather than voxel by voxel: a voxel-exact sphere cost a brick evaluation
// per 4 x 4 voxels of its surface (LiDAR scans at 30 m and 5 cm: 235,000
// bricks a scan) and as much map; the steps leave about 1% of the voxels a
// ray truncated at max_range would clear unknown (the outer 1/64 of its
// length, half of it on average). Where that node would be smaller than a
// brick (a short range at a coarse resolution), range_depth is 0 and the
// test is the voxel's own: (x x + y y) + z z <= max_range^2 in float.
//
// Arithmetic. The rule is evaluated in float, exactly as written here, so
// that a vectorised evaluation and a plain one agree bit for bit: p is the
// camera-frame centre of the brick's first voxel (computed in double,
// rounded to float) plus the voxel's offset in the brick (offset_table, in
// double, rounded to float); 1 / z, then u = (x * (1 / z)) * fx + (cx + 1/2)
// and likewise v, in float, each required to lie within +-2^24 (so that
// cells are exact integers); the reading test z < d - margin. The decisions about whole
// nodes (projective_tracer.cpp) are made in double with margins that cover
// the difference, so they never contradict this rule.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "umbra/core/grid.hpp"
#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/integrate/depth_image.hpp"
#include "integrate/depth_pyramid.hpp"
#include "integrate/ray_tracer.hpp"
#include "integrate/surface_band.hpp"

namespace umbra {

class OccupancyTree;
class UpdateBatch;

struct ProjectiveFrame {
  int width = 0;
  int height = 0;
  std::vector<float> depth;  ///< metres, row by row; 0: no reading
  /// Images of scans (scan_images.hpp): what a voxel reads at level 0 in
  /// each half pixel, (2 width) x (2 height): the half's nearest reading
  /// where it has one, else its pixel's nearest (0 where the pixel has
  /// none); `depth` holds each pixel's nearest. Empty for depth images (one
  /// reading a pixel).
  std::vector<float> depth_halves;
  /// With depth_halves: the largest of each pixel's four halves (the
  /// pyramid's maxima start from it).
  std::vector<float> farthest_half;
  DepthPyramid pyramid;      ///< of `depth` (its maxima of depth_halves' where there are)

  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  /// Map to camera: p = rotation * (c - origin); row r is camera axis r in the map frame.
  std::array<std::array<double, 3>, 3> rotation{};
  Vec3d origin;

  /// Takes the image (its depths converted to float metres), intrinsics and
  /// pose. Throws std::invalid_argument for a pose that is not a rotation.
  void set(const DepthImage& image, const PinholeCamera& camera, const Pose& pose);

  [[nodiscard]] Vec3d to_camera(Vec3d world) const { return rotate(world - origin); }
  /// A map-frame direction in the camera frame.
  [[nodiscard]] Vec3d rotate(Vec3d d) const {
    return {rotation[0][0] * d.x + rotation[0][1] * d.y + rotation[0][2] * d.z,
            rotation[1][0] * d.x + rotation[1][1] * d.y + rotation[1][2] * d.z,
            rotation[2][0] * d.x + rotation[2][1] * d.y + rotation[2][2] * d.z};
  }
  /// The image's rays: those of pixel p end at ray_ends[ray_order[k]] (at
  /// ray_ends[k] when ray_order is empty) for k in [pixel_rays[p],
  /// pixel_rays[p + 1]). ray_ends is not owned.
  std::span<const Vec3f> ray_ends;
  std::vector<std::uint32_t> pixel_rays;
  std::vector<std::uint32_t> ray_order;
  /// Sets the rays: ray i ends at ends[i] and its pixel is pixels[i].
  void set_rays(std::span<const Vec3f> ends, std::span<const std::uint32_t> pixels);

  [[nodiscard]] std::size_t memory_bytes() const {
    return (depth.capacity() + depth_halves.capacity() + farthest_half.capacity()) * sizeof(float) +
           pyramid.memory_bytes() +
           (pixel_rays.capacity() + ray_order.capacity()) * sizeof(std::uint32_t);
  }
};

/// Everything the rule reads for one scan, in the float form it is evaluated in.
struct ProjectiveRule {
  const Grid* grid = nullptr;
  const ProjectiveFrame* frame = nullptr;
  float fx = 0.0f;
  float fy = 0.0f;
  float cx_half = 0.0f;  ///< cx + 1/2
  float cy_half = 0.0f;  ///< cy + 1/2
  float width = 0.0f;
  float height = 0.0f;
  float margin = 0.0f;             ///< metres; a voxel passes when z < d - margin
  double max_range = -1.0;         ///< <= 0: unlimited
  int range_depth = 0;             ///< max_range applies to nodes of this depth, 0 or >= 2 (file comment)
  float max_range_squared = 0.0f;  ///< range_depth 0: the per-voxel test's bound
  float half_voxel_pixels = 0.0f;  ///< min(fx, fy) * resolution / 2: w = this / z
  /// The seen unit (file comment, "Seen units"): a voxel clears only when
  /// every voxel of its depth-`seen_depth` node is seen: 0 the voxel
  /// itself, 1 its group of eight, 2 its brick (fine resolutions: also
  /// turns on cells and off the surface band).
  int seen_depth = 0;
  /// The default of seen_depth at this resolution, for a depth image or
  /// the image of a scan (scan_images.hpp).
  static int seen_unit_depth(double resolution, bool scan_image);
  /// `cleared` (a brick's voxels, bit i: voxel i) less the voxels of the
  /// depth-`seen_depth` nodes not all of whose voxels are in `seen`.
  [[nodiscard]] static std::uint64_t keep_seen_units(std::uint64_t cleared, std::uint64_t seen, int seen_depth);
  float edge_reach = 0.0f;         ///< pixel-metres: a centre projecting this / z pixels outside the image reads its edge
  float width_inside = 0.0f;       ///< width - 1/2: the projection clamped into the image
  float height_inside = 0.0f;      ///< height - 1/2
  float centre_dz = 0.0f;          ///< camera-frame z of the brick's centre minus its first voxel's
  int top_level = 0;               ///< the pyramid's top level
  /// Camera-frame offset of brick voxel i (Morton index, 0..63) from the brick's first voxel.
  std::array<std::array<float, 64>, 3> offset_table{};
  std::array<float, 3> offset_min{};  ///< per axis, the least of offset_table's 64 entries
  std::array<float, 3> offset_max{};  ///< and the largest
  std::optional<KeyBox> box_keys;  ///< only voxels in it change
  /// The map before this scan (known obstacles: see the file comment), or
  /// none (then no voxel is held as an obstacle).
  const OccupancyTree* tree = nullptr;
  float occupied_log_odds = 0.0f;  ///< above this, a voxel is an obstacle
  /// Where set, voxels near the surface are decided by the rays
  /// (surface_band.hpp); the walk and apply_surface_band read it.
  std::optional<SurfaceBand> surface_band;

  ProjectiveRule(const Grid& grid, const ProjectiveFrame& frame, double max_range, double margin,
                 const std::optional<KeyBox>& box_keys);

  /// The rule on the grids of 2, 4, ... times the resolution (see "Cells"
  /// in the file comment): cells[c - 1] is level c, whose cells are the
  /// depth-c nodes; none until use_cells().
  struct CellLevel;
  std::vector<std::shared_ptr<const CellLevel>> cells;
  /// Decides far nodes by cells where the file comment says so, cells at
  /// most `widest` metres wide.
  static constexpr double kWidestCell = 0.01;
  /// Cells are used where they are narrower than this many pixels.
  static constexpr float kCellPixels = 4.0f;
  void use_cells(double widest = kWidestCell);
  /// Whether cells decide the depth-`depth` node whose first voxel is
  /// `first` (depth 2 + c for a level c of cells).
  [[nodiscard]] bool decided_by_cells(Key first, int depth) const;
  /// Adds the misses of the depth-`depth` node `node` (first voxel `first`,
  /// decided by cells) to `batch`, voxels outside `box` left out. `plain`:
  /// the definition, voxel by voxel (else the faster evaluation, bit for bit
  /// the same).
  void add_cell_misses(std::uint64_t node, Key first, int depth, bool plain, UpdateBatch& batch) const;
  /// The mask of the voxels of brick `brick` inside box_keys (all without a box).
  [[nodiscard]] std::uint64_t brick_voxels_in_box(std::uint64_t brick) const;

  /// Whether every voxel centre of the depth-`range_depth` node holding
  /// finest voxel `voxel` is within max_range of the camera (true without a
  /// range, or with range_depth 0: then the voxels are tested one by one).
  [[nodiscard]] bool within_range(Key voxel) const;
  /// Whether every voxel centre of the depth-`depth` node `code` is within
  /// max_range (`farthest`), and whether none is (`nearest`), in double.
  struct CentreDistances {
    double nearest_squared;
    double farthest_squared;
  };
  /// (For the depth-`depth` node whose first voxel is `first`.)
  [[nodiscard]] CentreDistances centre_distances(Key first, int depth) const;

  /// Camera-frame centre of voxel `first` (a brick's first voxel), in
  /// float as the rule uses it.
  [[nodiscard]] Vec3f brick_origin(Key first) const;
  /// The window level of a brick whose first voxel is at `origin` (camera frame).
  [[nodiscard]] int window_level(Vec3f origin) const;

  /// Whether one of the image's rays passes through finest voxel `code` and
  /// ends beyond it (see the file comment).
  [[nodiscard]] bool ray_crosses(std::uint64_t code) const;


  /// The voxels of the brick the rule clears (bit i: voxel brick + i; the
  /// box and known obstacles not applied), voxel by voxel: the definition
  /// (voxel_verdicts, then keep_seen_units).
  [[nodiscard]] std::uint64_t cleared_plain(std::uint64_t brick) const;
  /// Each voxel of the brick on its own, before the seen unit applies:
  /// those that pass the reading test (cleared) and those seen.
  struct VoxelVerdicts {
    std::uint64_t cleared;
    std::uint64_t seen;
  };
  [[nodiscard]] VoxelVerdicts voxel_verdicts(std::uint64_t brick) const;
  /// The same, eight voxels at a time where the CPU has AVX2 (bit for bit
  /// the same: a test compares them).
  [[nodiscard]] std::uint64_t cleared(std::uint64_t brick) const;
  /// cleared() for a brick known to be within range, whose first voxel is `first`.
  [[nodiscard]] std::uint64_t cleared_in_range(std::uint64_t brick, Key first) const;
  /// The rule's answer for a whole brick (first voxel at `origin` in the
  /// camera frame, window level `level`) when bounds decide it: 0 (clears
  /// nothing) or all 64 bits; none when some voxels may differ. Bounds, not
  /// an estimate: float rounding is monotonic, so the voxels' float
  /// coordinates, projections and cells lie between those of the brick's
  /// extreme offsets (see the .cpp), and the answer is cleared_plain's.
  /// (Asked of depth-3 and -4 nodes too, with bounds over their bricks'
  /// origins, it decided more of them but saved no time on the TUM frames.)
  [[nodiscard]] std::optional<std::uint64_t> whole_brick(Vec3f origin, int level) const;
};

struct ProjectiveRule::CellLevel {
  CellLevel(const Grid& finest, int c, const ProjectiveFrame& frame, double margin)
      : grid(std::ldexp(finest.resolution(), c), finest.depth_levels() - c),
        rule(grid, frame, -1.0, margin, std::nullopt) {}
  CellLevel(const CellLevel&) = delete;  // `rule` points at `grid`
  CellLevel& operator=(const CellLevel&) = delete;

  Grid grid;            ///< 2^c times the resolution, c depth levels fewer
  ProjectiveRule rule;  ///< on `grid`; the finest grid's range and edge reach, no box
};

namespace detail {
/// Whether the segment from `o` to `end` (cut at max_range when > 0)
/// passes through the cube [lo, hi) and ends outside it (OctoMap's ray from
/// o to end visits that voxel before its end voxel, up to rounding).
bool segment_crosses(Vec3d o, Vec3d end, double max_range, Vec3d lo, Vec3d hi);
/// Whether this build and CPU can run projective_cleared_avx2.
bool projective_avx2_available();
/// ProjectiveRule::cleared with AVX2, for a brick whose first voxel is at
/// `origin` and whose window level is `level`.
std::uint64_t projective_cleared_avx2(const ProjectiveRule& rule, Vec3f origin, int level);
}  // namespace detail

}  // namespace umbra
