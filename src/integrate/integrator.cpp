#include "integrate/integrator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "core/radix_sort.hpp"
#include "core/voxel_codes.hpp"
#include "integrate/brick_hits.hpp"
#include "integrate/scan_images.hpp"
#include "integrate/color_samples.hpp"
#include "integrate/end_voxels.hpp"
#include "integrate/projective_tracer.hpp"
#include "integrate/ray_order.hpp"
#include "ray/ray_direction.hpp"

namespace umbra {

IntegratorKind parse_integrator_kind(const std::string& name) {
  if (name == "simple") return IntegratorKind::simple;
  if (name == "discrete") return IntegratorKind::discrete;
  if (name == "fast") return IntegratorKind::fast;
  if (name == "projective") return IntegratorKind::projective;
  throw std::invalid_argument("unknown integrator '" + name + "' (expected simple, discrete, fast or projective)");
}

const char* to_string(IntegratorKind kind) {
  switch (kind) {
    case IntegratorKind::simple: return "simple";
    case IntegratorKind::discrete: return "discrete";
    case IntegratorKind::fast: return "fast";
    case IntegratorKind::projective: return "projective";
  }
  return "?";
}

void InsertOptions::validate(int depth_levels) const {
  if (std::isnan(max_range)) throw std::invalid_argument("max_range is NaN");
  if (clear_depth < -1 || clear_depth > depth_levels) {
    throw std::invalid_argument("clear_depth must be -1 (automatic) or in [0, " + std::to_string(depth_levels) +
                                "], got " + std::to_string(clear_depth));
  }
  if (fine_steps < 0) throw std::invalid_argument("fine_steps must be >= 0, got " + std::to_string(fine_steps));
  for (const double resolution : {scan_resolution.horizontal, scan_resolution.vertical}) {
    if (!(resolution >= 0.0 && resolution < 0.5)) {
      throw std::invalid_argument("scan_resolution must be 0 (estimated) or a positive number of radians below 0.5 on "
                                  "each axis, got " + std::to_string(resolution));
    }
  }
  if (!(surface_margin >= 0.0 && std::isfinite(surface_margin))) {
    throw std::invalid_argument("surface_margin must be finite and >= 0, got " + std::to_string(surface_margin));
  }
  if (threads > max_threads()) {
    throw std::invalid_argument("threads must be at most " + std::to_string(max_threads()) + " (4 per hardware thread, " +
                                std::to_string(hardware_threads()) + " here; at least 16), got " +
                                std::to_string(threads));
  }
  if (stamp && !std::isfinite(*stamp)) throw std::invalid_argument("stamp must be finite, got " + std::to_string(*stamp));
}

int InsertOptions::resolved_clear_depth(const Grid& grid) const {
  if (clear_depth >= 0) return clear_depth;
  // The depth whose node edge is closest to 16 cm on a log scale.
  const double ideal = std::log2(0.16 / grid.resolution());
  const int depth = static_cast<int>(std::lround(ideal));
  return std::clamp(depth, 0, grid.depth_levels());
}

InsertStats& InsertStats::operator+=(const InsertStats& other) {
  points += other.points;
  rays += other.rays;
  hits += other.hits;
  truncated += other.truncated;
  non_finite += other.non_finite;
  out_of_bounds += other.out_of_bounds;
  outside_box += other.outside_box;
  threads = std::max(threads, other.threads);
  exclusive_seconds += other.exclusive_seconds;
  if (other.scan_resolution.horizontal > 0.0) scan_resolution = other.scan_resolution;
  return *this;
}

namespace {

/// Subtrees per thread the projective integrator's walk is split into (trace_projective_misses).
constexpr std::size_t kTasksPerThread = 64;

/// The voxels of the map that a box covers (the box is cut to the map).
KeyBox key_box(const Grid& grid, const Aabb& box) {
  const double inside = grid.half_extent() - 0.5 * grid.resolution();
  auto clamp = [inside](Vec3d p) {
    return Vec3d{std::clamp(p.x, -inside, inside), std::clamp(p.y, -inside, inside), std::clamp(p.z, -inside, inside)};
  };
  return {grid.key(clamp(box.min)), grid.key(clamp(box.max))};
}


/// A hit for the end voxel `code` of the discrete integrator's ray from
/// `origin`: unless its centre lies beyond max_range, or (with a box) the
/// ray to it is clipped by the box or the voxel lies outside the box's keys
/// (counted in `stats`). False when it had one already.
bool add_end_voxel_hit(const Grid& grid, Vec3f origin, std::uint64_t code, double max_range,
                       const std::optional<Aabb>& box, const std::optional<KeyBox>& box_keys, UpdateBatch& batch,
                       InsertStats& stats) {
  const Key key = morton::decode(code);
  const Vec3f centre = grid.center_f(key);
  if (max_range > 0.0 && octomap_norm_exceeds(centre - origin, max_range)) {
    ++stats.truncated;
    return false;
  }
  if (box) {
    const auto part = box->clip(Vec3d(origin), Vec3d(centre));
    if (!part || part->second < 1.0 || !box_keys->contains(key)) {
      ++stats.outside_box;
      return false;
    }
  }
  return batch.add_hit(code);
}

/// The discrete integrator's hits for a scan's points: the voxel of every
/// point in the map whose centre lies within max_range of the origin (and,
/// with a box, in it: the discrete integrator's ray to that centre is not
/// clipped), each voxel once.
void add_end_voxel_hits(const Grid& grid, Vec3f origin, std::span<const Vec3f> points, double max_range,
                        const std::optional<Aabb>& box, const std::optional<KeyBox>& box_keys, UpdateBatch& batch,
                        InsertStats& stats) {
  constexpr std::size_t kBlock = 1024;
  std::array<std::uint64_t, kBlock> codes;
  std::uint64_t last = kNonFiniteCode;
  for (std::size_t block = 0; block < points.size(); block += kBlock) {
    const std::size_t size = std::min(kBlock, points.size() - block);
    voxel_codes(grid, points.subspan(block, size), codes.data());
    for (std::size_t j = 0; j < size; ++j) {
      const std::uint64_t code = codes[j];
      if (code >= kOutsideCode) {
        ++(code == kNonFiniteCode ? stats.non_finite : stats.out_of_bounds);
        continue;
      }
      if (code == last) continue;  // neighbouring points share voxels: most repeats come in a row
      last = code;
      if (add_end_voxel_hit(grid, origin, code, max_range, box, box_keys, batch, stats)) ++stats.hits;
    }
  }
  stats.rays = stats.hits;
}

}  // namespace

Integrator::Integrator() = default;
Integrator::~Integrator() = default;
Integrator::Integrator(Integrator&&) noexcept = default;
Integrator& Integrator::operator=(Integrator&&) noexcept = default;

void Integrator::ensure_workers(unsigned threads) {
  if (threads > 1 && (!pool_ || pool_->requested() != threads)) pool_ = std::make_unique<ThreadPool>(threads);
  while (tracers_.size() < threads) tracers_.push_back(std::make_unique<RayTracer>());
}

ThreadPool* Integrator::workers(unsigned threads) {
  if (threads == 0) threads = ThreadPool::hardware_threads();
  ensure_workers(threads);
  return threads > 1 ? pool_.get() : nullptr;
}

std::size_t Integrator::memory_bytes() const {
  std::size_t bytes = tracers_.capacity() * sizeof(tracers_[0]);
  if (pool_) bytes += sizeof(ThreadPool) + pool_->size() * sizeof(std::thread);
  for (const auto& tracer : tracers_) bytes += sizeof(RayTracer) + tracer->memory_bytes();
  return bytes + frame_.memory_bytes() + scan_images_.memory_bytes() + image_points_.memory_bytes();
}

InsertStats Integrator::trace(const OccupancyTree& tree, const Grid& grid, Vec3f origin,
                              std::span<const Vec3f> points, std::span<const Rgb> colors,
                              const InsertOptions& options, const std::optional<Aabb>& box) {
  discard();
  options.validate(grid.depth_levels());
  if (!colors.empty() && colors.size() != points.size()) {
    throw std::invalid_argument("one color per point expected: " + std::to_string(colors.size()) + " colors, " +
                                std::to_string(points.size()) + " points");
  }
  if (!colors.empty() && !tree.has_color()) throw std::invalid_argument("colors given to a map without color");
  if (!origin.is_finite()) {
    throw std::invalid_argument("sensor origin is not finite: (" + std::to_string(origin.x) + ", " +
                                std::to_string(origin.y) + ", " + std::to_string(origin.z) + ")");
  }
  if (box) box->validate();

  const Key origin_key = grid.key(Vec3d(origin));  // throws std::out_of_range with the coordinate and the extent
  if (options.integrator == IntegratorKind::projective && grid.depth_levels() >= 2) {
    return trace_scan_projective(tree, grid, origin, points, colors, options, box);
  }

  ScanContext scan;
  scan.grid = &grid;
  scan.origin = origin;
  scan.origin_key = origin_key;
  scan.max_range = options.max_range;
  scan.clear_depth = options.resolved_clear_depth(grid);
  // Clearing depth-0 "nodes" is clearing voxels: tracing every ray voxel by
  // voxel does that exactly, and faster than grouping rays per voxel.
  scan.fast = options.integrator == IntegratorKind::fast && scan.clear_depth > 0;
  scan.fine_steps = options.fine_steps;
  // Clear nodes of 32^3 voxels and more that may not be cleared whole are
  // split, level by level, into children cleared whole where allowed, down
  // to nodes of 2^3 voxels, which are walked voxel by voxel. Without it a
  // 2 mm map's 12.8 cm nodes near the noisy surfaces of a depth image were
  // walked voxel by voxel: 6.8 s and 8.4 GB for the ten TUM frames' map per
  // frame, against 1.2 s and 450 MiB with it; 4 mm: 1.16 s -> 0.88 s per
  // frame, 1005 -> 173 MiB. For smaller nodes each split costs more than the
  // walk it saves (1 cm: 222 ms -> 350 ms per frame).
  scan.walk_depth = scan.clear_depth >= 5 ? 1 : scan.clear_depth;
  scan.tree = &tree;
  if (box) {
    scan.box = box;
    scan.box_keys = key_box(grid, *box);
  }

  InsertStats stats;
  stats.points = points.size();
  const unsigned threads = options.threads == 0 ? ThreadPool::hardware_threads() : options.threads;
  ensure_workers(threads);
  stats.threads = threads > 1 ? pool_->size() : 1;  // fewer when the system refused to start some
  for (unsigned w = 0; w < threads; ++w) tracers_[w]->start(grid.depth_levels());
  std::vector<InsertStats> worker_stats(threads);
  // Runs `work(begin, end, worker, chunk)` over [0, count) in `chunks`
  // contiguous chunks (neighbouring rays stay in one batch; several chunks
  // per worker balance uneven rays). Any worker may run any chunk.
  auto split = [&](std::size_t count, std::size_t chunks, const auto& work) {
    if (threads == 1) {
      for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
        work(count * chunk / chunks, count * (chunk + 1) / chunks, 0u, chunk);
      }
      return;
    }
    pool_->run(chunks, [&](std::size_t chunk, unsigned worker) {
      work(count * chunk / chunks, count * (chunk + 1) / chunks, worker, chunk);
    });
  };
  const std::size_t ray_chunks = std::size_t{threads} * 8;

  std::vector<Vec3f> centres;
  std::span<const Vec3f> ends = points;
  if (options.integrator != IntegratorKind::simple) {
    // One ray per end voxel, in Morton order of the end voxels (which keeps
    // consecutive rays on nearby paths): to the voxel centre (discrete,
    // OctoMap's computeDiscreteUpdate), or to the first point that fell in
    // the voxel (fast: its rays then cross the voxels the simple
    // integrator's would; rays to centres cleared 2% of the surface voxels
    // differently from it on depth-camera frames at 2 cm). The voxels are
    // found, sorted and made unique in parallel, a part of the scan per
    // thread, and the parts merged (end_voxels.hpp).
    if (points.size() > std::numeric_limits<std::uint32_t>::max()) {
      throw std::invalid_argument("too many points in one scan: " + std::to_string(points.size()));
    }
    std::vector<std::vector<EndVoxel>> parts(threads);
    std::vector<InsertStats> part_stats(threads);
    split(points.size(), threads, [&](std::size_t begin, std::size_t end, unsigned, std::size_t chunk) {
      end_voxels(grid, points, begin, end - begin, parts[chunk], part_stats[chunk]);
    });
    for (const InsertStats& s : part_stats) stats += s;
    const std::vector<EndVoxel> voxels = merge_end_voxels(parts);
    centres.reserve(voxels.size());
    for (const EndVoxel& v : voxels) {
      centres.push_back(options.integrator == IntegratorKind::fast ? points[v.point]
                                                                   : grid.center_f(morton::decode(v.code)));
    }
    ends = centres;
  }

  if (!scan.fast) {
    split(ends.size(), ray_chunks, [&](std::size_t begin, std::size_t end, unsigned worker, std::size_t) {
      InsertStats chunk_stats;  // not worker_stats[worker] per ray: it shares a cache line with the neighbour's
      tracers_[worker]->trace(scan, ends.subspan(begin, end - begin), chunk_stats);
      worker_stats[worker] += chunk_stats;
    });
  } else {
    // The rays and the voxels that get a hit (finest codes), prepared in
    // parallel. Each part is filled in locals and handed over at the end:
    // writing the neighbouring vectors and stats of the parts per ray from
    // two threads shared their cache lines and made this loop 2.8x slower
    // per ray (CPU time of the TUM frames at 2 cm: 22 ms on one thread, 60
    // ms on two).
    std::vector<std::vector<PreparedRay>> ray_parts(threads);
    std::vector<std::vector<std::uint64_t>> hit_parts(threads);
    std::vector<InsertStats> prepare_stats(threads);
    split(ends.size(), threads, [&](std::size_t begin, std::size_t end, unsigned, std::size_t chunk) {
      std::vector<PreparedRay> part;
      std::vector<std::uint64_t> hits;
      InsertStats part_stats;
      part.reserve(end - begin);
      hits.reserve(end - begin);
      for (std::size_t i = begin; i < end; ++i) {
        PreparedRay& ray = part.emplace_back();  // prepared in place: a copy of a fresh ray stalled (prepare_ray)
        if (!prepare_ray(scan, ends[i], &part_stats, ray)) {
          part.pop_back();
          continue;
        }
        part_stats.hits += ray.hit;
        if (ray.hit && (!scan.box_keys || scan.box_keys->contains(ray.end_key))) hits.push_back(ray.end_code);
      }
      ray_parts[chunk] = std::move(part);
      hit_parts[chunk] = std::move(hits);
      prepare_stats[chunk] = part_stats;
    });
    for (const InsertStats& s : prepare_stats) stats += s;
    // Two independent jobs, side by side when there are threads (one after
    // the other they were 60% of the serial work of a two-thread insertion
    // of the TUM frames at 2 cm, 2.3 ms per frame):
    //  - the hits into tracer 0's batch: every tracer must know all hits of
    //    the scan to decide which coarse nodes it may clear whole. They come
    //    in the order of the sorted rays: their ends are the sorted end
    //    voxels (only truncated or clipped ends, which give no hit, move);
    //  - the rays in order of their ends, in groups whose ends share a
    //    coarse node, each led by one guide ray.
    std::vector<PreparedRay> rays;
    std::vector<std::size_t> group_begin;
    const auto add_hits = [&] { tracers_[0]->add_hits(scan, hit_parts); };
    const auto group_rays = [&] {
      rays = rays_in_end_order(ray_parts, 3 * grid.depth_levels());
      std::vector<std::vector<PreparedRay>>().swap(ray_parts);
      const int shift = 3 * scan.clear_depth;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        if (i == 0 || rays[i].end_code >> shift != rays[i - 1].end_code >> shift) group_begin.push_back(i);
      }
      group_begin.push_back(rays.size());
    };
    if (threads == 1) {
      add_hits();
      group_rays();
    } else {
      pool_->run(2, [&](std::size_t job, unsigned) { job == 0 ? add_hits() : group_rays(); });
    }
    for (unsigned w = 1; w < threads; ++w) tracers_[w]->batch() = tracers_[0]->batch();
    scan.hits_first = true;
    const std::span<const PreparedRay> all(rays);
    split(group_begin.size() - 1, ray_chunks, [&](std::size_t begin, std::size_t end, unsigned worker, std::size_t) {
      OccupancyTree::Cursor cursor(tree);
      for (std::size_t g = begin; g < end; ++g) {
        tracers_[worker]->trace_group(scan, all.subspan(group_begin[g], group_begin[g + 1] - group_begin[g]), cursor);
      }
    });
  }
  for (const InsertStats& s : worker_stats) stats += s;

  UpdateBatch& batch = tracers_[0]->batch();
  for (unsigned w = 1; w < threads; ++w) {
    batch.merge(tracers_[w]->batch(), /*with_hits=*/!scan.fast);
    tracers_[w]->start(grid.depth_levels());  // give its memory back
  }
  ThreadPool* const pool = threads > 1 ? pool_.get() : nullptr;
  if (!colors.empty()) pending_colors_ = color_samples(grid, origin, points, colors, options, scan.box_keys, pool);
  pending_threads_ = threads;
  pending_batches_ = 1;
  return stats;
}

InsertStats Integrator::trace_image(const OccupancyTree& tree, const Grid& grid, const DepthImage& image,
                                    const PinholeCamera& camera, const Pose& pose, std::span<const Rgb> colors,
                                    const InsertOptions& options, const std::optional<Aabb>& box) {
  discard();
  options.validate(grid.depth_levels());
  camera.validate();
  if (!colors.empty() && colors.size() != image.pixel_count()) {
    throw std::invalid_argument("one color per pixel expected: " + std::to_string(colors.size()) + " colors, " +
                                std::to_string(image.pixel_count()) + " pixels");
  }
  if (!colors.empty() && !tree.has_color()) throw std::invalid_argument("colors given to a map without color");
  if (!pose.is_rigid()) {
    throw std::invalid_argument("the camera pose must be a rotation and a translation (an orthonormal 3x3 part with "
                                "determinant 1, all finite)");
  }
  const unsigned threads = options.threads == 0 ? ThreadPool::hardware_threads() : options.threads;
  ensure_workers(threads);
  ThreadPool* const pool = threads > 1 ? pool_.get() : nullptr;
  // A map of one depth level has no bricks (the projective rule's unit): it
  // takes the image's points as the discrete integrator does.
  const bool projective = options.integrator == IntegratorKind::projective && grid.depth_levels() >= 2;
  // The points' voxels on every worker; the projective rule's image (its
  // pyramid) meanwhile. The projective integrator reads only the voxels (and
  // the points themselves for colors and for the surface band's rays).
  image_points_.build(
      grid, image, camera, pose, colors, pool, [&] {
        if (projective) frame_.set(image, camera, pose);
      },
      /*voxels_only=*/projective);
  // Its rays, for the voxels near the surface (surface_band.hpp), where there can be any.
  if (projective && SurfaceBand::possible(grid.resolution(), frame_, options.max_range)) {
    image_points_.keep_points(image, camera, pose);
    frame_.set_rays(image_points_.points(), image_points_.pixels());
  } else {
    frame_.ray_ends = {};
    std::vector<std::uint32_t>().swap(frame_.pixel_rays);  // no memory where unused
  }
  const Vec3f origin = pose.translation();
  if (!projective) {
    InsertOptions point_options = options;
    if (point_options.integrator == IntegratorKind::projective) point_options.integrator = IntegratorKind::discrete;
    return trace(tree, grid, origin, image_points_.points(), image_points_.colors(), point_options, box);
  }
  if (box) box->validate();
  (void)grid.key(Vec3d(origin));  // throws std::out_of_range with the coordinate and the extent
  std::optional<KeyBox> box_keys;
  if (box) box_keys = key_box(grid, *box);

  InsertStats stats;
  stats.points = image.pixel_count();
  stats.non_finite = image_points_.non_finite();
  stats.out_of_bounds = image_points_.out_of_bounds();
  stats.threads = threads > 1 ? pool_->size() : 1;
  for (unsigned w = 0; w < threads; ++w) tracers_[w]->start(grid.depth_levels());
  // The hits (the discrete integrator's: the voxels holding a point) and the
  // color samples are side jobs, each on one worker while the others trace
  // misses (serial, but off the critical path). A depth image's rays are as
  // dense as its pixels: the rule alone decides its misses, known obstacles
  // included (projective_frame.hpp).
  // On several threads the hits go to the batches of the subtrees that hold
  // them instead (hits_in), so that no batch holds hits all over the image.
  InsertStats hit_stats;
  const auto add_hits_in = [&](std::uint64_t first, std::uint64_t end, UpdateBatch& batch, InsertStats& counts) {
    if (box) {  // each voxel's ray clipped by the box
      image_points_.for_each_voxel_in(first, end, [&](std::uint64_t code) {
        if (add_end_voxel_hit(grid, origin, code, options.max_range, box, box_keys, batch, counts)) ++counts.hits;
      });
      return;
    }
    // The voxels come a brick at a time, sorted (brick_hits.hpp).
    BrickHits hits(grid, origin, options.max_range, batch, counts);
    image_points_.for_each_brick_in(first, end, [&](BrickVoxels voxels) { hits.add(voxels); });
    hits.flush();
  };
  const auto side_job = [&](std::size_t job, UpdateBatch& batch) {
    if (job == 0) {
      add_hits_in(0, ~std::uint64_t{0}, batch, hit_stats);
    } else {
      queue_end_voxel_colors(grid, origin, image_points_.points(), image_points_.colors(), image_points_.codes(),
                             options, box_keys);
    }
  };
  const HitsInRange hits_in(add_hits_in);
  trace_projective_misses(nullptr, grid, options, box_keys, std::span<const ProjectiveFrame>(&frame_, 1), threads,
                          colors.empty() ? 1 : 2, side_job, &hits_in, &hit_stats);
  stats.hits = hit_stats.hits;
  stats.truncated = hit_stats.truncated;
  stats.outside_box = hit_stats.outside_box;
  stats.rays = stats.hits;
  pending_threads_ = threads;
  return stats;
}

void Integrator::queue_end_voxel_colors(const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                                        std::span<const Rgb> colors, std::span<const std::uint64_t> codes,
                                        const InsertOptions& options, const std::optional<KeyBox>& box_keys) {
  // The projective integrator's hits are the discrete integrator's: so are its colors.
  InsertOptions discrete = options;
  discrete.integrator = IntegratorKind::discrete;
  pending_colors_ = color_samples(grid, origin, points, colors, discrete, box_keys, nullptr, codes);
}

InsertStats Integrator::trace_scan_projective(const OccupancyTree& tree, const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                                              std::span<const Rgb> colors, const InsertOptions& options,
                                              const std::optional<Aabb>& box) {
  std::optional<KeyBox> box_keys;
  if (box) box_keys = key_box(grid, *box);
  InsertStats stats;
  stats.points = points.size();
  const unsigned threads = options.threads == 0 ? ThreadPool::hardware_threads() : options.threads;
  ensure_workers(threads);
  stats.threads = threads > 1 ? pool_->size() : 1;
  for (unsigned w = 0; w < threads; ++w) tracers_[w]->start(grid.depth_levels());
  // The hits and the color samples are side jobs, each on one worker while
  // the others trace misses.
  const auto side_job = [&](std::size_t job, UpdateBatch& batch) {
    if (job == 0) {
      add_end_voxel_hits(grid, origin, points, options.max_range, box, box_keys, batch, stats);
    } else {
      queue_end_voxel_colors(grid, origin, points, colors, {}, options, box_keys);
    }
  };
  const std::size_t side_jobs = colors.empty() ? 1 : 2;
  const ScanResolution resolution = estimate_scan_resolution(origin, points, options.scan_resolution);
  if (resolution.horizontal > 0.0 && resolution.vertical > 0.0) {
    stats.scan_resolution = resolution;
    scan_images_.build(origin, points, resolution);
    trace_projective_misses(&tree, grid, options, box_keys, scan_images_.faces(), threads, side_jobs, side_job);
  } else {
    for (std::size_t job = 0; job < side_jobs; ++job) side_job(job, tracers_[0]->batch());
    pending_batches_ = 1;
  }
  pending_threads_ = threads;
  return stats;
}

void Integrator::trace_projective_misses(const OccupancyTree* tree, const Grid& grid, const InsertOptions& options,
                                         const std::optional<KeyBox>& box_keys,
                                         std::span<const ProjectiveFrame> frames, unsigned threads,
                                         std::size_t side_jobs, FunctionRef<void(std::size_t, UpdateBatch&)> side_job,
                                         const HitsInRange* hits_in, InsertStats* hit_stats) {
  // One rule and tracer per image (the six faces of a scan, or one depth
  // image); a voxel gets a miss when any of them clears it.
  std::vector<ProjectiveRule> rules;
  rules.reserve(frames.size());
  for (const ProjectiveFrame& frame : frames) {
    ProjectiveRule& rule =
        rules.emplace_back(grid, frame, options.max_range, options.surface_margin * grid.resolution(), box_keys);
    if (tree != nullptr) {
      rule.tree = tree;
      rule.occupied_log_odds = tree->thresholds().occupied;
    }
    rule.use_cells();  // depth images at fine resolutions (projective_frame.hpp)
    // Depth images at coarse resolutions (surface_band.hpp).
    rule.surface_band = SurfaceBand::make(rule, &band_image_);
  }
  const int root_depth = grid.depth_levels();
  if (threads == 1) {
    for (std::size_t job = 0; job < side_jobs; ++job) side_job(job, tracers_[0]->batch());
    for (const ProjectiveRule& rule : rules) ProjectiveTracer(rule).trace(0, root_depth, tracers_[0]->batch());
    pending_batches_ = 1;
    return;
  }
  // Subtrees for the threads: the nodes the walks open, down to the first
  // depth that yields kTasksPerThread per thread. The work is where the
  // surfaces are, so subtrees are very uneven: with 16 a thread, the two
  // workers' CPU time in a TUM frame's trace at 4 mm differed by up to 6x
  // (118 and 19 ms); with 64 mostly within 1.1x (job CPU accounting,
  // umbra_insert_benchmark --serial-share).
  struct Task {
    std::size_t image;
    ProjectiveTracer::Task node;
  };
  std::vector<Task> tasks;
  std::vector<ProjectiveTracer::Task> nodes;
  // Not below the nodes cells may decide (projective_frame.hpp): those are traced whole.
  int lowest = 2;
  for (const ProjectiveRule& rule : rules) lowest = std::max(lowest, 2 + static_cast<int>(rule.cells.size()));
  // Each depth's tasks from the last's: a node split there is collected one
  // level down (collect's own recursion, so the tasks are those of one
  // collect from the root to that depth, in the same order). Collecting
  // from the root again for every depth was a serial 0.27 ms of a TUM
  // frame's 14 ms on two threads at 2 cm.
  std::vector<Task> coarser;
  for (int depth = std::max(root_depth - 1, lowest); depth >= lowest; --depth) {
    tasks.clear();
    if (depth == std::max(root_depth - 1, lowest)) {
      for (std::size_t i = 0; i < rules.size(); ++i) {
        nodes.clear();
        ProjectiveTracer(rules[i]).collect(0, root_depth, depth, nodes);
        for (const ProjectiveTracer::Task& node : nodes) tasks.push_back({i, node});
      }
    } else {
      std::optional<ProjectiveTracer> tracer;  // the last task's image's
      std::size_t tracer_image = 0;
      for (const Task& task : coarser) {
        if (task.node.depth <= depth || task.node.decision == ProjectiveTracer::Decision::all) {
          tasks.push_back(task);
          continue;
        }
        if (!tracer || tracer_image != task.image) {
          tracer.emplace(rules[task.image]);
          tracer_image = task.image;
        }
        nodes.clear();
        for (std::uint64_t slot = 0; slot < 8; ++slot) {
          tracer->collect(task.node.code | slot << (3 * depth), depth, depth, nodes);
        }
        for (const ProjectiveTracer::Task& node : nodes) tasks.push_back({task.image, node});
      }
    }
    if (tasks.size() >= std::size_t{threads} * kTasksPerThread || depth == lowest) break;
    coarser.swap(tasks);
  }
  // Hits routed to the tasks need the tasks disjoint and in code order: one image's are (collect).
  const bool route_hits = hits_in != nullptr && rules.size() == 1;
  std::vector<InsertStats> task_hit_stats(route_hits ? tasks.size() + 1 : 0);  // the last: outside every task
  const auto task_end = [](const Task& task) { return task.node.code + (std::uint64_t{1} << (3 * task.node.depth)); };
  // The side jobs are the first tasks: the pool hands tasks out in order, so they start first.
  pool_->run(side_jobs + tasks.size(), [&](std::size_t i, unsigned worker) {
    UpdateBatch& batch = tracers_[worker]->batch();
    if (i < side_jobs) {
      if (i > 0 || !route_hits) {
        side_job(i, batch);
        return;
      }
      std::uint64_t first = 0;  // the hits between the tasks
      InsertStats& counts = task_hit_stats.back();
      for (const Task& task : tasks) {
        if (task.node.code > first) (*hits_in)(first, task.node.code, batch, counts);
        first = task_end(task);
      }
      (*hits_in)(first, ~std::uint64_t{0}, batch, counts);
      return;
    }
    const Task& task = tasks[i - side_jobs];
    ProjectiveTracer(rules[task.image]).trace(task.node.code, task.node.depth, batch);
    if (route_hits) (*hits_in)(task.node.code, task_end(task), batch, task_hit_stats[i - side_jobs]);
  });
  // In a fixed order: the counts do not depend on which worker ran what.
  for (const InsertStats& counts : task_hit_stats) *hit_stats += counts;
  pending_batches_ = threads;
}

void Integrator::apply(OccupancyTree& tree, const SensorModel& sensor) {
  if (pending_threads_ == 0) throw std::logic_error("Integrator::apply: nothing traced");
  const unsigned threads = pending_threads_;
  pending_threads_ = 0;
  tree.apply(pending_batches(), sensor.hit_log_odds(), sensor.miss_log_odds(), threads > 1 ? pool_.get() : nullptr);
  for (unsigned w = 0; w < pending_batches_; ++w) tracers_[w]->start(tree.depth_levels());
  pending_batches_ = 0;
  if (!pending_colors_.empty()) tree.add_colors(pending_colors_, threads > 1 ? pool_.get() : nullptr);
  std::vector<OccupancyTree::ColorSample>().swap(pending_colors_);
}

std::vector<const UpdateBatch*> Integrator::pending_batches() const {
  std::vector<const UpdateBatch*> batches;
  for (unsigned w = 0; w < pending_batches_; ++w) batches.push_back(&tracers_[w]->batch());
  return batches;
}

void Integrator::discard() {
  pending_threads_ = 0;  // the next trace() empties the batches
  pending_batches_ = 0;
  std::vector<OccupancyTree::ColorSample>().swap(pending_colors_);
}

}  // namespace umbra
