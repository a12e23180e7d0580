// `umbra query` end to end: the answers of the program equal the library's
// on the same map, for every kind, with unknown blocking and free, at depth
// 0 and coarser; malformed lines are reported with their line numbers and
// get no answer; stderr's last line is the timing as one JSON object.
#include <algorithm>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/query_oracle.hpp"
#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/query/distance_field.hpp"

namespace umbra {
namespace {

using test::cli;
using test::quoted;

struct CliRun {
  int exit_code;
  std::vector<std::string> out;  // stdout lines
  std::vector<std::string> err;  // stderr lines
};

CliRun run_query(const std::string& arguments, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "out.txt";
  const std::filesystem::path err = dir / "err.txt";
  const test::CommandResult r =
      test::run_command("( " + cli() + " query " + arguments + " > " + quoted(out) + " 2> " + quoted(err) + " )");
  CliRun run{r.exit_code, {}, {}};
  auto lines = [](const std::filesystem::path& path) {
    std::vector<std::string> v;
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) v.push_back(line);
    return v;
  };
  run.out = lines(out);
  run.err = lines(err);
  return run;
}

/// Checks stderr's last line is the timing object for `queries` queries.
void expect_timing(const CliRun& run, const std::string& kind, std::size_t queries) {
  ASSERT_FALSE(run.err.empty());
  const std::regex json("^\\{\"kind\": \"" + kind + "\", \"queries\": " + std::to_string(queries) +
                        ", \"seconds\": [0-9.e+-]+, \"us_per_query\": [0-9.e+-]+\\}$");
  EXPECT_TRUE(std::regex_match(run.err.back(), json)) << run.err.back();
}

class QueryCli : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::scratch_dir();
    test::RandomMapSpec spec;
    spec.depth_levels = 6;
    spec.seed = 31;
    spec.block_fill = 0.3;
    map_ = std::make_unique<OccupancyMap>(test::random_map(spec));
    save_map(*map_, dir_ / "map.umb");
  }

  std::filesystem::path write_lines(const std::vector<std::string>& lines) {
    const std::filesystem::path path = dir_ / "queries.txt";
    std::ofstream out(path);
    for (const std::string& line : lines) out << line << '\n';
    return path;
  }

  std::filesystem::path dir_;
  std::unique_ptr<OccupancyMap> map_;
};

std::string text(const std::vector<double>& values) {
  std::ostringstream s;
  s.precision(17);
  for (std::size_t i = 0; i < values.size(); ++i) s << (i ? " " : "") << values[i];
  return s.str();
}

TEST_F(QueryCli, AnswersEqualTheLibrarysForEveryKind) {
  std::mt19937 rng(4);
  const double h = map_->grid().half_extent() * 0.9;
  std::uniform_real_distribution<double> u(-h, h);
  std::uniform_real_distribution<double> r(0.02, 0.6);
  std::ptrdiff_t collisions = 0;
  std::ptrdiff_t clear = 0;
  for (const bool unknown_free : {false, true}) {
    for (const int depth : {0, 2}) {
      const CollisionOptions options{unknown_free, depth};
      const std::string common = " --unknown " + std::string(unknown_free ? "free" : "blocks") + " --depth " +
                                 std::to_string(depth);
      std::vector<std::string> spheres, boxes, lines, rays;
      std::vector<bool> sphere_hits, box_hits, line_hits, capsule_hits;
      std::vector<std::string> ray_answers;
      for (int i = 0; i < 60; ++i) {
        const Vec3d c{u(rng) * 0.7, u(rng) * 0.7, u(rng) * 0.7};
        const double radius = r(rng);
        spheres.push_back(text({c.x, c.y, c.z, radius}));
        sphere_hits.push_back(!map_->is_free(Sphere{c, radius}, options).free);
        const Vec3d a{u(rng), u(rng), u(rng)};
        const Vec3d b = a + Vec3d{0.3 * radius, 0.2, 0.5 * radius};
        boxes.push_back(text({a.x, a.y, a.z, b.x, b.y, b.z}));
        box_hits.push_back(!map_->is_free(Aabb{a, b}, options).free);
        const Vec3d p{u(rng) * 0.8, u(rng) * 0.8, u(rng) * 0.8};
        const Vec3d q{u(rng) * 0.8, u(rng) * 0.8, u(rng) * 0.8};
        lines.push_back(text({p.x, p.y, p.z, q.x, q.y, q.z}));
        line_hits.push_back(!map_->is_free(Segment{p, q}, options).free);
        capsule_hits.push_back(!map_->is_free(Capsule{p, q, 0.1}, options).free);
        const double range = i % 2 ? -1.0 : 2.0 * radius;
        rays.push_back(text({p.x, p.y, p.z, q.x - p.x, q.y - p.y, q.z - p.z, range}));
        const RayHit hit = map_->cast_ray(p, q - p, {range, false, depth});
        char expected[128];
        std::snprintf(expected, sizeof expected, "1 %.10g %.10g %.10g", hit.node.center.x, hit.node.center.y,
                      hit.node.center.z);
        ray_answers.push_back(hit.hit ? expected : "0");
      }
      auto check = [&](const std::string& kind, const std::vector<std::string>& input,
                       const std::vector<bool>& expected, const std::string& extra) {
        SCOPED_TRACE(kind + common + extra);
        const CliRun run = run_query(quoted(dir_ / "map.umb") + " " + kind + " --input " + quoted(write_lines(input)) +
                                      common + extra,
                                  dir_);
        ASSERT_EQ(run.exit_code, 0) << (run.err.empty() ? "" : run.err.front());
        ASSERT_EQ(run.out.size(), expected.size());
        for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(run.out[i], expected[i] ? "1" : "0") << i;
        expect_timing(run, kind, expected.size());
      };
      check("sphere", spheres, sphere_hits, "");
      check("box", boxes, box_hits, "");
      check("line", lines, line_hits, "");
      check("line", lines, capsule_hits, " --radius 0.1");
      const CliRun run = run_query(quoted(dir_ / "map.umb") + " raycast --input " + quoted(write_lines(rays)) + common, dir_);
      ASSERT_EQ(run.exit_code, 0);
      EXPECT_EQ(run.out, ray_answers);
      expect_timing(run, "raycast", rays.size());
      collisions += std::count(sphere_hits.begin(), sphere_hits.end(), true);
      clear += std::count(sphere_hits.begin(), sphere_hits.end(), false);
    }
  }
  // Both answers occurred.
  EXPECT_GT(collisions, 0);
  EXPECT_GT(clear, 0);
}

TEST_F(QueryCli, GainEqualsTheLibrarysForBothMethodsAndTheGivenFieldOfView) {
  std::mt19937 rng(9);
  const double h = map_->grid().half_extent() * 0.6;
  std::uniform_real_distribution<double> u(-h, h);
  std::uniform_real_distribution<double> yaw(-180.0, 180.0);
  std::uniform_real_distribution<double> pitch(-30.0, 30.0);
  std::vector<std::string> poses;
  std::vector<std::vector<double>> values;
  for (int i = 0; i < 25; ++i) {
    values.push_back({u(rng), u(rng), u(rng), yaw(rng), pitch(rng)});
    poses.push_back(text(values.back()));
  }
  std::uint64_t seen = 0;
  for (const std::string method : {"exact", "fast"}) {
    // A narrower view and ranges other than the defaults, so the options must reach the frustum.
    const std::string flags = " --method " + method + " --hfov 70 --vfov 40 --min-range 0.1 --max-range 1.5";
    SCOPED_TRACE(flags);
    const CliRun run = run_query(quoted(dir_ / "map.umb") + " gain --input " + quoted(write_lines(poses)) + flags, dir_);
    ASSERT_EQ(run.exit_code, 0) << (run.err.empty() ? "" : run.err.front());
    ASSERT_EQ(run.out.size(), poses.size());
    GainOptions options;
    options.method = method == std::string("fast") ? GainMethod::fast : GainMethod::exact;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const std::vector<double>& v = values[i];
      const GainResult want =
          map_->information_gain(Frustum::from_degrees({v[0], v[1], v[2]}, v[3], v[4], 70, 40, 0.1, 1.5), options);
      char expected[96];
      std::snprintf(expected, sizeof expected, "%llu %.10g", static_cast<unsigned long long>(want.unknown_voxels),
                    want.volume);
      EXPECT_EQ(run.out[i], expected) << "pose " << i;
      seen += want.unknown_voxels;
    }
    expect_timing(run, "gain", poses.size());
  }
  EXPECT_GT(seen, 0u);  // the poses see unknown space at all
  // A field of view that cannot be is a usage error, before any line is read.
  const CliRun bad = run_query(quoted(dir_ / "map.umb") + " gain --input - --hfov 0 < /dev/null", dir_);
  EXPECT_EQ(bad.exit_code, 2);
}

TEST_F(QueryCli, DistanceEqualsTheLibrarysField) {
  std::mt19937 rng(17);
  const double h = map_->grid().half_extent() * 0.9;
  std::uniform_real_distribution<double> u(-h, h);
  std::vector<std::string> lines;
  std::vector<Vec3d> points;
  for (int i = 0; i < 40; ++i) {
    points.push_back({u(rng), u(rng), u(rng)});
    lines.push_back(text({points.back().x, points.back().y, points.back().z}));
  }
  lines.insert(lines.begin() + 5, "1 2");  // a bad line: no answer, reported with its number
  for (const int depth : {0, 1}) {
    SCOPED_TRACE("depth " + std::to_string(depth));
    const CliRun run = run_query(quoted(dir_ / "map.umb") + " distance --max-distance 0.35 --depth " +
                                     std::to_string(depth) + " --input " + quoted(write_lines(lines)),
                                 dir_);
    EXPECT_EQ(run.exit_code, 1);
    ASSERT_EQ(run.out.size(), points.size());
    ASSERT_GE(run.err.size(), 2u);
    EXPECT_NE(run.err.front().find("line 6"), std::string::npos) << run.err.front();
    DistanceFieldOptions options;
    options.max_distance = 0.35;
    options.depth = depth;
    const DistanceField field(*map_, options);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const DistanceSample s = field.distance_and_gradient(points[i]);
      char expected[160];
      std::snprintf(expected, sizeof expected, "%.10g %.10g %.10g %.10g %.10g", s.occupied, s.unknown, s.gradient.x,
                    s.gradient.y, s.gradient.z);
      EXPECT_EQ(run.out[i], expected) << "point " << i;
    }
    expect_timing(run, "distance", points.size());
  }
  // A maximum distance the field cannot hold is a usage error.
  const CliRun bad = run_query(quoted(dir_ / "map.umb") + " distance --max-distance 1000 --input - < /dev/null", dir_);
  EXPECT_EQ(bad.exit_code, 2);
}

TEST_F(QueryCli, NodesListAndCountEqualTheLibrarys) {
  for (const std::string state : {"occupied", "free", "unknown"}) {
    for (const int depth : {0, 3}) {
      SCOPED_TRACE(state + " at depth " + std::to_string(depth));
      const Predicate p = pred::leaf() && (state == "occupied" ? pred::occupied()
                                           : state == "free"   ? pred::free()
                                                               : pred::unknown());
      const std::string args = quoted(dir_ / "map.umb") + " nodes --state " + state + " --depth " + std::to_string(depth);
      const CliRun count = run_query(args + " --count", dir_);
      ASSERT_EQ(count.exit_code, 0);
      ASSERT_EQ(count.out.size(), 1u);
      EXPECT_EQ(count.out[0], std::to_string(map_->count(p, depth)));
      const CliRun list = run_query(args, dir_);
      ASSERT_EQ(list.exit_code, 0);
      std::vector<std::string> expected;
      for (const Node& n : map_->query(p, depth)) {
        char line[160];
        std::snprintf(line, sizeof line, "%.10g %.10g %.10g %.10g %s", n.center.x, n.center.y, n.center.z, n.size,
                      to_string(n.state));
        expected.push_back(line);
      }
      EXPECT_EQ(list.out, expected);
      EXPECT_GT(expected.size(), 0u);
    }
  }
  // Within a sphere and a box.
  const CliRun in_sphere = run_query(quoted(dir_ / "map.umb") + " nodes --state occupied --sphere 0.1,0.2,0.3,1.5 --count", dir_);
  ASSERT_EQ(in_sphere.exit_code, 0);
  EXPECT_EQ(in_sphere.out.at(0),
            std::to_string(map_->count(pred::leaf() && pred::occupied() && pred::intersects(Sphere{{0.1, 0.2, 0.3}, 1.5}))));
  const CliRun in_box = run_query(quoted(dir_ / "map.umb") + " nodes --box -1,-1,-1,0.5,0.5,0.5 --count", dir_);
  ASSERT_EQ(in_box.exit_code, 0);
  EXPECT_EQ(in_box.out.at(0), std::to_string(map_->count(pred::leaf() && pred::intersects(Aabb{{-1, -1, -1}, {0.5, 0.5, 0.5}}))));
}

TEST_F(QueryCli, MalformedLinesAreReportedByNumberAndTheRestIsAnswered) {
  const std::vector<std::string> input = {
      "0.1 0.2 0.3 0.4",       // 1: good
      "",                      // 2: blank, skipped
      "# a comment",           // 3: skipped
      "0.1 0.2 0.3",           // 4: too few numbers
      "0.1 0.2 zero 0.4",      // 5: not a number
      "0.1 0.2 0.3 nan",       // 6: not finite
      "500 0 0 0.1",           // 7: outside the map
      "0.1 0.2 0.3 -1",        // 8: negative radius
      "-0.5 0.5 0.2 0.1",      // 9: good
  };
  const CliRun run = run_query(quoted(dir_ / "map.umb") + " sphere --input " + quoted(write_lines(input)), dir_);
  EXPECT_EQ(run.exit_code, 1);
  ASSERT_EQ(run.out.size(), 2u);  // lines 1 and 9
  EXPECT_EQ(run.out[0], map_->is_free(Sphere{{0.1, 0.2, 0.3}, 0.4}).free ? "0" : "1");
  EXPECT_EQ(run.out[1], map_->is_free(Sphere{{-0.5, 0.5, 0.2}, 0.1}).free ? "0" : "1");
  std::string err;
  for (const std::string& line : run.err) err += line + "\n";
  EXPECT_NE(err.find("line 4: expected 4 numbers (x y z r), found 3"), std::string::npos) << err;
  EXPECT_NE(err.find("line 5: 'zero' is not a finite number"), std::string::npos) << err;
  EXPECT_NE(err.find("line 6: 'nan' is not a finite number"), std::string::npos) << err;
  EXPECT_NE(err.find("line 7: "), std::string::npos) << err;
  EXPECT_NE(err.find("outside the map"), std::string::npos) << err;
  EXPECT_NE(err.find("line 8: sphere radius must be finite and >= 0"), std::string::npos) << err;
  EXPECT_EQ(err.find("line 2"), std::string::npos);
  EXPECT_EQ(err.find("line 3"), std::string::npos);
  expect_timing(run, "sphere", 4);  // lines 1, 7, 8, 9 reached the library

  // Usage errors: exit code 2.
  // No --input reads standard input, or is a usage error on a terminal (cli_usability_test.cpp).
  EXPECT_EQ(run_query(quoted(dir_ / "map.umb") + " cone --input x", dir_).exit_code, 2);
  EXPECT_EQ(run_query(quoted(dir_ / "map.umb") + " nodes --depth 9", dir_).exit_code, 2);
  EXPECT_EQ(run_query(quoted(dir_ / "map.umb") + " nodes --sphere 0,0,0,-1", dir_).exit_code, 2);
}

}  // namespace
}  // namespace umbra
