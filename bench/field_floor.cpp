// The floor under any exact per-scan update of the distance field, measured
// on the field benchmark's scans and box against dynamicEDT3D's update() in
// the same run (docs/benchmarks.md, "Distance field", round nine). After
// each scan, in thread CPU time:
//   - dynamicEDT3D's update() (unknown as occupied: one field) and umbra's
//     update() (both distances kept); at the end umbra's rebuild of the box
//     (its own transform's cost a cell, against the bare one's);
//   - the changed cells: those of the box whose answer changes, read from
//     umbra's field at every cell centre before and after its update
//     (d_occupied, d_unknown, the gradient; "blocking": min(d_occupied,
//     d_unknown) or the gradient, what a one-kind field such as
//     dynamicEDT3D's with unknown as occupied answers). Any exact field with
//     this API writes at least these cells (fewer than its stored sites
//     change: a new site as near as the old one is not counted);
//   - the cost per cell of the fastest exact transform known here:
//     Felzenszwalb and Huttenlocher's linear-time separable transform, dense
//     over the box, one kind at a time, squared distances only (no sites
//     kept, no cap, centre-to-centre metric: each a simplification that
//     makes it cheaper than umbra's transform);
//   - floor A: changed cells x that cost, a transform whose work is exactly
//     the changed cells and nothing else;
//   - floor B: the same three passes run over exactly the lines through
//     changed cells (pass x on the rows that hold one, pass y and z on the
//     columns), each only from the first to the last changed cell of the
//     line and reading the inputs within the window (max_distance in cells)
//     of those, from the dense passes' inputs. Not an exact update (a changed
//     cell's z column reads y results of lines with no change), a floor for
//     any update built on the separable transform;
//   - scheme C: an exact incremental separable transform that keeps both
//     passes' outputs of the previous scan (2 x 4 bytes a cell per kind
//     more): pass x again on the rows whose sites changed, pass y on the
//     columns whose pass-x values changed, pass z on those whose pass-y
//     values changed (values beyond the cap count as equal: the capped
//     field does not depend on them), each line's outputs within the window
//     of its changed inputs, from the inputs within the window of those.
//     Exact, so its time is what such a design would pay for the passes
//     (finding the lines not included).
// The sites come from the same answers (distance 0: the cell is a site).
// Not included in either floor: reading the changes from the tree, finding
// the changed cells, storing them.
//
//   umbra_field_floor [--data-dir DIR] [--datasets tum,3dtk] [--max-distance 1.0] [--check]
// --check: only compares the transform with a brute force on random grids
// and scheme C with the dense transform after random changes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <dynamicEDT3D/dynamicEDTOctomap.h>
#include <octomap/OcTree.h>

#include "bench_data.hpp"
#include "common/argument_cursor.hpp"
#include "field_datasets.hpp"
#include "umbra/field/distance_field.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using umbra::bench::thread_cpu_seconds;

constexpr std::uint32_t kFar = 1u << 30;  // no site on the line (any real squared distance is smaller)
constexpr int kKinds = 3;                 // occupied, unknown, blocking (either)
const char* const kKindNames[kKinds] = {"occupied", "unknown", "blocking"};

/// The dense box: cells [0, n) per axis, x fastest.
struct Grid3 {
  int nx = 0, ny = 0, nz = 0;
  [[nodiscard]] std::size_t cells() const { return std::size_t(nx) * std::size_t(ny) * std::size_t(nz); }
  [[nodiscard]] std::size_t index(int x, int y, int z) const {
    return (std::size_t(z) * std::size_t(ny) + std::size_t(y)) * std::size_t(nx) + std::size_t(x);
  }
};

/// Felzenszwalb and Huttenlocher's separable squared Euclidean transform
/// (centre to centre), one kind, with each pass callable on chosen lines.
/// A part of a line: the input positions read and the output positions written.
struct Segment {
  int in_lo, in_hi, out_lo, out_hi;  // inclusive
};

class SeparableTransform {
 public:
  explicit SeparableTransform(const Grid3& g)
      : g_(g), pass_x_(g.cells()), pass_y_(g.cells()), out_(g.cells()) {
    const std::size_t longest = std::size_t(std::max({g.nx, g.ny, g.nz}));
    in_.resize(longest);
    hull_.resize(longest);
    bounds_.resize(longest + 1);
  }

  /// Pass x on row (y, z): squared distance to the row's nearest site (bit
  /// `mask` of sites) among those in the segment's input.
  void row_x(const std::vector<std::uint8_t>& sites, std::uint8_t mask, int y, int z, Segment s) {
    const std::size_t at = g_.index(0, y, z);
    const std::uint8_t* row = &sites[at];
    std::uint32_t* dest = &pass_x_[at];
    int last = -1;
    for (int x = s.in_lo; x <= s.out_hi; ++x) {
      if (row[x] & mask) last = x;
      if (x >= s.out_lo) dest[x] = last < 0 ? kFar : std::uint32_t((x - last) * (x - last));
    }
    int next = -1;
    for (int x = s.in_hi; x >= s.out_lo; --x) {
      if (row[x] & mask) next = x;
      if (next >= 0 && x <= s.out_hi) dest[x] = std::min(dest[x], std::uint32_t((next - x) * (next - x)));
    }
  }
  /// Pass y on column (x, z) of pass x's output.
  void column_y(int x, int z, Segment s) {
    line(&pass_x_[g_.index(x, 0, z)], std::size_t(g_.nx), &pass_y_[g_.index(x, 0, z)], s);
  }
  /// Pass z on column (x, y) of pass y's output.
  void column_z(int x, int y, Segment s) {
    line(&pass_y_[g_.index(x, y, 0)], std::size_t(g_.nx) * std::size_t(g_.ny), &out_[g_.index(x, y, 0)], s);
  }
  /// All three passes over the whole box.
  void dense(const std::vector<std::uint8_t>& sites, std::uint8_t mask) {
    const Segment row{0, g_.nx - 1, 0, g_.nx - 1}, column_y_all{0, g_.ny - 1, 0, g_.ny - 1},
        column_z_all{0, g_.nz - 1, 0, g_.nz - 1};
    for (int z = 0; z < g_.nz; ++z) {
      for (int y = 0; y < g_.ny; ++y) row_x(sites, mask, y, z, row);
    }
    for (int z = 0; z < g_.nz; ++z) {
      for (int x = 0; x < g_.nx; ++x) column_y(x, z, column_y_all);
    }
    for (int y = 0; y < g_.ny; ++y) {
      for (int x = 0; x < g_.nx; ++x) column_z(x, y, column_z_all);
    }
  }
  [[nodiscard]] std::uint32_t at(std::size_t i) const { return out_[i]; }
  [[nodiscard]] const std::vector<std::uint32_t>& pass_x() const { return pass_x_; }
  [[nodiscard]] const std::vector<std::uint32_t>& pass_y() const { return pass_y_; }

 private:
  /// out[t] = min over s of values[s] + (t - s)^2 for s in the segment's
  /// input, t in its output: the lower envelope of the sites' parabolas,
  /// gathered into a contiguous line first (strided reads of a z column are
  /// the pass' cost otherwise).
  void line(const std::uint32_t* values, std::size_t stride, std::uint32_t* out, Segment seg) {
    const int n = seg.in_hi - seg.in_lo + 1;
    const std::uint32_t* first = values + std::size_t(seg.in_lo) * stride;
    for (int i = 0; i < n; ++i) in_[std::size_t(i)] = first[std::size_t(i) * stride];
    int k = -1;
    for (int q = 0; q < n; ++q) {
      const std::int64_t fq = in_[std::size_t(q)];
      if (fq >= kFar) continue;
      double s = -std::numeric_limits<double>::infinity();
      while (k >= 0) {
        const int p = hull_[std::size_t(k)];
        const std::int64_t fp = in_[std::size_t(p)];
        s = double((fq + std::int64_t(q) * q) - (fp + std::int64_t(p) * p)) / double(2 * (q - p));
        if (s > bounds_[std::size_t(k)]) break;
        --k;
      }
      ++k;
      hull_[std::size_t(k)] = q;
      bounds_[std::size_t(k)] = s;
    }
    if (k < 0) {
      for (int t = seg.out_lo; t <= seg.out_hi; ++t) out[std::size_t(t) * stride] = kFar;
      return;
    }
    bounds_[std::size_t(k) + 1] = std::numeric_limits<double>::infinity();
    int j = 0;
    for (int t = seg.out_lo - seg.in_lo; t <= seg.out_hi - seg.in_lo; ++t) {
      while (bounds_[std::size_t(j) + 1] < double(t)) ++j;
      const int p = hull_[std::size_t(j)];
      out[std::size_t(t + seg.in_lo) * stride] = in_[std::size_t(p)] + std::uint32_t((t - p) * (t - p));
    }
  }

  Grid3 g_;
  std::vector<std::uint32_t> pass_x_, pass_y_, out_;
  std::vector<std::uint32_t> in_;
  std::vector<int> hull_;
  std::vector<double> bounds_;
};

/// One cell's answer, compact: both distances and a hash of the gradient.
struct Answer {
  float occupied = -1, unknown = -1;
  std::uint32_t gradient = 0;
  friend bool operator==(const Answer&, const Answer&) = default;
};

std::uint32_t gradient_hash(const umbra::Vec3d& g) {
  std::uint64_t h = 1469598103934665603ull;
  const double v[3] = {g.x, g.y, g.z};
  unsigned char bytes[sizeof(v)];
  std::memcpy(bytes, v, sizeof(v));
  for (const unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
  return std::uint32_t(h ^ (h >> 32));
}

/// Per kind, the lines through changed cells (pass x: rows (y, z); y: (x,
/// z); z: (x, y)), each with the span of its changed positions (lo > hi:
/// none).
struct ChangedLines {
  struct Span {
    int lo = std::numeric_limits<int>::max(), hi = -1;
    void add(int p) {
      lo = std::min(lo, p);
      hi = std::max(hi, p);
    }
  };
  std::vector<Span> rows_x, columns_y, columns_z;
  std::size_t cells = 0;
  void reset(const Grid3& g) {
    rows_x.assign(std::size_t(g.ny) * std::size_t(g.nz), Span{});
    columns_y.assign(std::size_t(g.nx) * std::size_t(g.nz), Span{});
    columns_z.assign(std::size_t(g.nx) * std::size_t(g.ny), Span{});
    cells = 0;
  }
  void mark(const Grid3& g, int x, int y, int z) {
    rows_x[std::size_t(z) * std::size_t(g.ny) + std::size_t(y)].add(x);
    columns_y[std::size_t(z) * std::size_t(g.nx) + std::size_t(x)].add(y);
    columns_z[std::size_t(y) * std::size_t(g.nx) + std::size_t(x)].add(z);
    ++cells;
  }
  [[nodiscard]] std::size_t lines() const {
    const auto marked = [](const std::vector<Span>& v) {
      return std::size_t(std::count_if(v.begin(), v.end(), [](const Span& s) { return s.lo <= s.hi; }));
    };
    return marked(rows_x) + marked(columns_y) + marked(columns_z);
  }
};

/// The segment of a line of `n` cells a changed span needs: outputs within
/// `out_margin` of the span, inputs within `window` of those (a capped
/// field's cell depends on the sites within the window only).
Segment segment(const ChangedLines::Span& span, int n, int out_margin, int window) {
  const int out_lo = std::max(0, span.lo - out_margin), out_hi = std::min(n - 1, span.hi + out_margin);
  return {std::max(0, out_lo - window), std::min(n - 1, out_hi + window), out_lo, out_hi};
}

/// One pass (0: x, 1: y, 2: z) over the lines of `lines`, each over the
/// segment its span needs (out_margin: 0 for the changed cells themselves,
/// `window` for the outputs a changed input can reach).
void time_changed_lines_pass(SeparableTransform& t, const Grid3& g, const std::vector<std::uint8_t>& sites,
                             std::uint8_t mask, const ChangedLines& lines, int out_margin, int window, int pass) {
  if (pass == 0) {
    for (int z = 0; z < g.nz; ++z) {
      for (int y = 0; y < g.ny; ++y) {
        const ChangedLines::Span& span = lines.rows_x[std::size_t(z) * std::size_t(g.ny) + std::size_t(y)];
        if (span.lo <= span.hi) t.row_x(sites, mask, y, z, segment(span, g.nx, out_margin, window));
      }
    }
  } else if (pass == 1) {
    for (int z = 0; z < g.nz; ++z) {
      for (int x = 0; x < g.nx; ++x) {
        const ChangedLines::Span& span = lines.columns_y[std::size_t(z) * std::size_t(g.nx) + std::size_t(x)];
        if (span.lo <= span.hi) t.column_y(x, z, segment(span, g.ny, out_margin, window));
      }
    }
  } else {
    for (int y = 0; y < g.ny; ++y) {
      for (int x = 0; x < g.nx; ++x) {
        const ChangedLines::Span& span = lines.columns_z[std::size_t(y) * std::size_t(g.nx) + std::size_t(x)];
        if (span.lo <= span.hi) t.column_z(x, y, segment(span, g.nz, out_margin, window));
      }
    }
  }
}

/// Thread CPU ms of the three passes over the lines of `lines` (above).
double time_changed_lines(SeparableTransform& t, const Grid3& g, const std::vector<std::uint8_t>& sites,
                          std::uint8_t mask, const ChangedLines& lines, int out_margin, int window) {
  const double start = thread_cpu_seconds();
  for (int pass = 0; pass < 3; ++pass) time_changed_lines_pass(t, g, sites, mask, lines, out_margin, window, pass);
  return 1e3 * (thread_cpu_seconds() - start);
}

/// The lines scheme C recomputes in one kind: rows whose sites changed,
/// then columns whose input pass changed (beyond `cap` all values count as equal).
ChangedLines incremental_lines(const Grid3& g, const std::vector<std::uint8_t>& old_sites,
                               const std::vector<std::uint8_t>& sites, std::uint8_t mask,
                               const std::vector<std::uint32_t>& old_x, const std::vector<std::uint32_t>& new_x,
                               const std::vector<std::uint32_t>& old_y, const std::vector<std::uint32_t>& new_y,
                               std::uint32_t cap) {
  ChangedLines lines;
  lines.reset(g);
  const auto differ = [cap](std::uint32_t a, std::uint32_t b) { return std::min(a, cap + 1) != std::min(b, cap + 1); };
  for (int z = 0; z < g.nz; ++z) {
    for (int y = 0; y < g.ny; ++y) {
      for (int x = 0; x < g.nx; ++x) {
        const std::size_t i = g.index(x, y, z);
        if ((old_sites[i] & mask) != (sites[i] & mask)) lines.rows_x[std::size_t(z) * std::size_t(g.ny) + std::size_t(y)].add(x);
        if (differ(old_x[i], new_x[i])) lines.columns_y[std::size_t(z) * std::size_t(g.nx) + std::size_t(x)].add(y);
        if (differ(old_y[i], new_y[i])) lines.columns_z[std::size_t(y) * std::size_t(g.nx) + std::size_t(x)].add(z);
      }
    }
  }
  return lines;
}

/// --check: the transform against a brute force on random grids (so that
/// its timings are those of an exact transform); true when all agree.
bool transform_matches_brute_force() {
  const Grid3 g{23, 17, 19};
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<std::uint8_t> sites(g.cells());
    for (std::uint8_t& s : sites) s = rng() % 100 < std::uint32_t(trial % 5) * 2 + 1 ? 1 : 0;  // 1% to 9% sites
    SeparableTransform t(g);
    t.dense(sites, 1);
    for (int z = 0; z < g.nz; ++z) {
      for (int y = 0; y < g.ny; ++y) {
        for (int x = 0; x < g.nx; ++x) {
          std::uint32_t best = kFar;
          for (int c = 0; c < g.nz; ++c) {
            for (int b = 0; b < g.ny; ++b) {
              for (int a = 0; a < g.nx; ++a) {
                if (sites[g.index(a, b, c)] != 0) {
                  best = std::min<std::uint32_t>(best, std::uint32_t((a - x) * (a - x) + (b - y) * (b - y) + (c - z) * (c - z)));
                }
              }
            }
          }
          if (std::min(best, kFar) != std::min(t.at(g.index(x, y, z)), kFar)) {
            std::printf("transform: cell (%d %d %d) of trial %d: %u, brute force %u\n", x, y, z, trial,
                        t.at(g.index(x, y, z)), best);
            return false;
          }
        }
      }
    }
  }
  std::printf("transform: equal to the brute force on 20 random grids\n");
  return true;
}

/// --check: scheme C (the passes again on the changed lines' segments only,
/// from the previous scan's passes) gives the dense transform's capped
/// field after random changes of the sites.
bool scheme_c_matches_dense() {
  const Grid3 g{41, 29, 23};
  const int window = 6;
  const std::uint32_t cap = window * window;
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<std::uint8_t> before(g.cells()), after;
    for (std::uint8_t& s : before) s = rng() % 100 < 2 ? 1 : 0;
    after = before;
    for (int change = 0; change < 1 + trial * 3; ++change) after[rng() % after.size()] ^= 1;
    SeparableTransform incremental(g), reference(g);
    incremental.dense(before, 1);
    reference.dense(after, 1);
    // The lines as the measurement finds them (the passes' changes within
    // the cap), then the passes on them only, from the previous passes.
    const ChangedLines lines = incremental_lines(g, before, after, 1, incremental.pass_x(), reference.pass_x(),
                                                 incremental.pass_y(), reference.pass_y(), cap);
    time_changed_lines(incremental, g, after, 1, lines, window, window);
    const auto beyond = [cap](std::uint32_t v) { return std::min(v, cap + 1); };
    for (std::size_t i = 0; i < g.cells(); ++i) {
      if (beyond(incremental.at(i)) != beyond(reference.at(i))) {
        std::printf("scheme C: cell %zu of trial %d: %u, dense %u\n", i, trial, incremental.at(i), reference.at(i));
        return false;
      }
    }
  }
  std::printf("scheme C: equal to the dense transform within the cap after 20 random changes\n");
  return true;
}

struct Options {
  std::string data_dir = "../shared/data";
  std::vector<std::string> datasets{"tum", "3dtk"};
  double max_distance = 1.0;
};

void run(const std::string& name, const Options& options) {
  umbra::bench::DatasetOptions data_options;
  data_options.data_dir = options.data_dir;
  const umbra::bench::Dataset data = umbra::bench::load_dataset(name, data_options);
  const double resolution = name == "tum" ? 0.02 : 0.05;
  umbra::OccupancyMap map(resolution);
  octomap::OcTree tree(resolution);
  umbra::InsertOptions insert;
  insert.max_range = data.max_range;
  const auto insert_scan = [&](const umbra::Scan& scan) {
    map.insert_point_cloud(scan.origin, scan.points, insert);
    octomap::Pointcloud cloud;
    for (const umbra::Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    tree.insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), data.max_range, false,
                          false);
  };
  insert_scan(data.scans[0]);
  const umbra::Aabb box = umbra::bench::field_dataset_box(name, umbra::Vec3d(data.scans[0].origin));
  umbra::DistanceFieldOptions field_options;
  field_options.max_distance = options.max_distance;
  field_options.box = box;
  umbra::DistanceField field(map, field_options);
  DynamicEDTOctomap edt(float(options.max_distance), &tree,
                        octomap::point3d(float(box.min.x), float(box.min.y), float(box.min.z)),
                        octomap::point3d(float(box.max.x), float(box.max.y), float(box.max.z)), true);
  edt.update();

  const umbra::Key lo = map.key(box.min), hi = map.key(box.max);
  Grid3 g;
  g.nx = int(hi.x - lo.x) + 1;
  g.ny = int(hi.y - lo.y) + 1;
  g.nz = int(hi.z - lo.z) + 1;
  std::printf("%s: %d x %d x %d cells (%.1f M), resolution %.2f m, max distance %.2f m\n", name.c_str(), g.nx, g.ny,
              g.nz, double(g.cells()) / 1e6, resolution, options.max_distance);
  std::vector<Answer> before(g.cells()), after(g.cells());
  std::vector<std::uint8_t> sites(g.cells());  // bit per kind
  std::vector<umbra::Vec3d> points(std::size_t(g.nx) * std::size_t(g.ny));
  std::vector<umbra::DistanceSample> samples(points.size());
  // Every cell centre's answer, and the sites (distance 0) per kind.
  const auto read_field = [&](std::vector<Answer>& answers) {
    for (int z = 0; z < g.nz; ++z) {
      std::size_t i = 0;
      for (int y = 0; y < g.ny; ++y) {
        for (int x = 0; x < g.nx; ++x) {
          points[i++] = map.grid().center(umbra::Key{lo.x + std::uint32_t(x), lo.y + std::uint32_t(y), lo.z + std::uint32_t(z)});
        }
      }
      field.distance_and_gradient(points, samples);
      for (std::size_t j = 0; j < samples.size(); ++j) {
        const std::size_t at = std::size_t(z) * samples.size() + j;
        const umbra::DistanceSample& s = samples[j];
        answers[at] = {float(s.occupied), float(s.unknown), gradient_hash(s.gradient)};
        sites[at] = std::uint8_t((s.occupied == 0.0 ? 1 : 0) | (s.unknown == 0.0 ? 2 : 0) |
                                 (s.blocking() == 0.0 ? 4 : 0));
      }
    }
  };
  read_field(before);
  // One transform per kind, and each one's sites and passes of the previous scan (scheme C).
  std::vector<std::unique_ptr<SeparableTransform>> transforms;
  std::vector<std::vector<std::uint32_t>> old_x(kKinds), old_y(kKinds);
  std::vector<std::uint8_t> old_sites = sites;
  for (int kind = 0; kind < kKinds; ++kind) {
    transforms.push_back(std::make_unique<SeparableTransform>(g));
    transforms.back()->dense(sites, std::uint8_t(1u << kind));
  }
  const double cells_cap = options.max_distance / resolution;
  const auto cap = std::uint32_t(std::ceil(cells_cap * cells_cap));
  const int window = int(std::ceil(cells_cap));  // cells on each side a capped cell depends on
  std::vector<ChangedLines> changed(kKinds);
  std::vector<double> edt_ms, umbra_ms, floor_a_both, floor_a_blocking, floor_b_both, floor_b_blocking, scheme_c_both,
      scheme_c_blocking;
  for (std::size_t scan = 1; scan < data.scans.size(); ++scan) {
    insert_scan(data.scans[scan]);
    double cpu = thread_cpu_seconds();
    edt.update();
    edt_ms.push_back(1e3 * (thread_cpu_seconds() - cpu));
    cpu = thread_cpu_seconds();
    field.update();
    umbra_ms.push_back(1e3 * (thread_cpu_seconds() - cpu));
    read_field(after);
    for (ChangedLines& c : changed) c.reset(g);
    for (int z = 0; z < g.nz; ++z) {
      for (int y = 0; y < g.ny; ++y) {
        for (int x = 0; x < g.nx; ++x) {
          const std::size_t i = g.index(x, y, z);
          const Answer& a = before[i];
          const Answer& b = after[i];
          if (a == b) continue;
          if (a.occupied != b.occupied) changed[0].mark(g, x, y, z);
          if (a.unknown != b.unknown) changed[1].mark(g, x, y, z);
          if (std::min(a.occupied, a.unknown) != std::min(b.occupied, b.unknown) || a.gradient != b.gradient) {
            changed[2].mark(g, x, y, z);
          }
        }
      }
    }
    double per_cell_ns[kKinds];
    double lines_ms[kKinds];
    double incremental_ms[kKinds];
    std::size_t incremental_lines_count[kKinds];
    for (int kind = 0; kind < kKinds; ++kind) {
      const std::uint8_t mask = std::uint8_t(1u << kind);
      SeparableTransform& transform = *transforms[std::size_t(kind)];
      old_x[std::size_t(kind)] = transform.pass_x();
      old_y[std::size_t(kind)] = transform.pass_y();
      cpu = thread_cpu_seconds();
      transform.dense(sites, mask);
      per_cell_ns[kind] = 1e9 * (thread_cpu_seconds() - cpu) / double(g.cells());
      lines_ms[kind] = time_changed_lines(transform, g, sites, mask, changed[std::size_t(kind)], 0, window);
      const ChangedLines incremental = incremental_lines(g, old_sites, sites, mask, old_x[std::size_t(kind)],
                                                         transform.pass_x(), old_y[std::size_t(kind)],
                                                         transform.pass_y(), cap);
      incremental_lines_count[kind] = incremental.lines();
      incremental_ms[kind] = time_changed_lines(transform, g, sites, mask, incremental, window, window);
    }
    old_sites = sites;
    const double a_both = 1e-6 * (double(changed[0].cells) * per_cell_ns[0] + double(changed[1].cells) * per_cell_ns[1]);
    const double a_blocking = 1e-6 * double(changed[2].cells) * per_cell_ns[2];
    floor_a_both.push_back(a_both);
    floor_a_blocking.push_back(a_blocking);
    floor_b_both.push_back(lines_ms[0] + lines_ms[1]);
    floor_b_blocking.push_back(lines_ms[2]);
    scheme_c_both.push_back(incremental_ms[0] + incremental_ms[1]);
    scheme_c_blocking.push_back(incremental_ms[2]);
    std::printf("%s update %zu: dynamicEDT3D %.1f ms, umbra %.1f ms (20x target %.1f ms)\n", name.c_str(), scan,
                edt_ms.back(), umbra_ms.back(), edt_ms.back() / 20.0);
    for (int kind = 0; kind < kKinds; ++kind) {
      std::printf("  %-8s changed cells %9zu, lines through them %7zu, dense transform %.2f ns a cell, "
                  "changed lines %.1f ms; scheme C %zu lines, %.1f ms\n",
                  kKindNames[kind], changed[std::size_t(kind)].cells, changed[std::size_t(kind)].lines(),
                  per_cell_ns[kind], lines_ms[kind], incremental_lines_count[kind], incremental_ms[kind]);
    }
    std::printf("  floor A (changed cells x dense cost): both kinds %.1f ms, blocking %.1f ms; floor B (changed "
                "lines): both kinds %.1f ms, blocking %.1f ms; scheme C: both kinds %.1f ms, blocking %.1f ms\n",
                a_both, a_blocking, floor_b_both.back(), floor_b_blocking.back(), scheme_c_both.back(),
                scheme_c_blocking.back());
    std::fflush(stdout);
    before.swap(after);
  }
  // umbra's own transform for comparison with the bare one: a rebuild of the
  // box (reading the sites from the tree included), both kinds.
  const double rebuild_cpu = thread_cpu_seconds();
  field.rebuild();
  const double rebuild_ms = 1e3 * (thread_cpu_seconds() - rebuild_cpu);
  std::printf("%s: umbra's rebuild of the box %.1f ms thread CPU, %.1f ns a cell for both kinds\n", name.c_str(),
              rebuild_ms, 1e6 * rebuild_ms / double(g.cells()));
  using umbra::bench::median;
  const double edt_median = median(edt_ms);
  std::printf("%s medians over %zu updates: dynamicEDT3D %.1f ms, umbra %.1f ms (%.2fx); floor A both kinds %.1f ms "
              "(%.1fx dynamicEDT3D's speed), blocking %.1f ms (%.1fx); floor B both kinds %.1f ms (%.1fx), blocking "
              "%.1f ms (%.1fx); scheme C both kinds %.1f ms (%.1fx), blocking %.1f ms (%.1fx)\n",
              name.c_str(), edt_ms.size(), edt_median, median(umbra_ms), edt_median / median(umbra_ms), median(floor_a_both),
              edt_median / median(floor_a_both), median(floor_a_blocking), edt_median / median(floor_a_blocking),
              median(floor_b_both), edt_median / median(floor_b_both), median(floor_b_blocking),
              edt_median / median(floor_b_blocking), median(scheme_c_both), edt_median / median(scheme_c_both),
              median(scheme_c_blocking), edt_median / median(scheme_c_blocking));
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string arg = args.flag();
    if (umbra::bench::take_dataset_flag(args, arg, options.data_dir, options.datasets)) continue;
    if (arg == "--max-distance") {
      options.max_distance = std::stod(args.value());
    } else if (arg == "--check") {
      const bool transform_ok = transform_matches_brute_force();
      const bool scheme_c_ok = scheme_c_matches_dense();
      return transform_ok && scheme_c_ok ? 0 : 1;
    } else {
      std::cerr << "usage: umbra_field_floor [--data DIR] [--datasets tum,3dtk] [--max-distance M] [--check]\n";
      return arg == "--help" ? 0 : 2;
    }
  }
  for (const std::string& name : options.datasets) run(name, options);
  return 0;
}
