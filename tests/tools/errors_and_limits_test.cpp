// The `umbra` program against hostile input and faults (issue 12): one exit
// code for bad usage, valid JSON, the pre-flight of `umbra build` (every
// input and the output checked before anything is inserted; what it saw is
// asserted from the program's own lines, never from the time it took),
// --keep-going, --max-memory, signals and kill -9 during a save, symbolic
// links, and a real process limit on threads.
//
// Processes that get signals are started with fork/exec and the test-only
// environment variable UMBRA_TEST_PAUSE_IN_SAVE, which makes every save wait
// after writing its temporary file's header, so the signal always arrives
// during the save. Waits for such a process are bounded (a hang detector);
// nothing here measures speed.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/map/map_statistics.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;

using test::cli;
using test::quoted;
using test::contains;
using test::run;

/// `n` points on the walls of a 4 m room around the origin.
std::vector<Vec3f> room_points(int n) {
  std::vector<Vec3f> points;
  points.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const float a = -1.9f + 3.8f * static_cast<float>(i % 997) / 997.0f;
    const float b = -1.9f + 3.8f * static_cast<float>((i / 997) % 991) / 991.0f;
    switch (i % 4) {
      case 0: points.push_back({2.0f, a, b}); break;
      case 1: points.push_back({-2.0f, a, b}); break;
      case 2: points.push_back({a, 2.0f, b}); break;
      default: points.push_back({a, -2.0f, b}); break;
    }
  }
  return points;
}

void write_xyz(const fs::path& path, const std::vector<Vec3f>& points) {
  std::ofstream out(path);
  out.precision(9);
  for (const Vec3f& p : points) out << p.x << ' ' << p.y << ' ' << p.z << '\n';
}

/// Leaves of a map as (code * 32 + depth, value), to compare maps.
std::vector<std::pair<std::uint64_t, float>> leaves(const OccupancyMap& map) {
  std::vector<std::pair<std::uint64_t, float>> out;
  map.for_each_leaf([&](const Node& n) { out.emplace_back(morton::encode(n.key) * 32 + n.depth, n.log_odds); });
  return out;
}

/// Names in `dir` that look like umbra's temporary files.
std::vector<std::string> temporaries_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.front() == '.' && contains(name, ".tmp-")) names.push_back(name);
  }
  return names;
}

// --- usage ---------------------------------------------------------------------

// Every non-physical value is a usage error (exit code 2), with the value and
// what is wrong in the message, and nothing is written.
TEST(ErrorsAndLimits, BadUsageIsExitCodeTwoWithTheValueInTheMessage) {
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "room.xyz", room_points(1000));
  const std::string build = "build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "out.umb") + " ";
  struct Case {
    std::string arguments;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {build + "--res nan", "the voxel edge in metres must be a number in [0.0001, 1000], got 'nan'"},
      {build + "--res inf", "got 'inf'"},
      {build + "--res 1e-300", "got '1e-300'"},
      {build + "--res 1e300", "got '1e300'"},
      {build + "--res 0", "got '0'"},
      {build + "--res -0.1", "got '-0.1'"},
      {build + "--res 0.00009", "got '0.00009'"},
      {build + "--res 1001", "got '1001'"},
      {build + "--threads 100000", "the number of threads (4 per core at most) must be a number in [0, " +
                                       std::to_string(max_threads()) + "], got '100000'"},
      {build + "--max-range nan", "expected a number, got 'nan'"},
      {build + "--depth-levels 22", "--depth-levels"},
      {build + "--origin 1,2", "--origin expects 3 numbers"},
      {build + "--origin 1,nan,2", "--origin expects 3 finite numbers"},
      {build + "--bbox 1,1,1,0,0,0", "bounding box: axis 0 must have finite min <= max"},
      {build + "--camera 0,1,1,1,1", "--camera: fx, fy and depth_scale must be > 0, got '0,1,1,1,1'"},
      {build + "--clear-depth 30", "--clear-depth"},
      {build + "--max-memory lots", "--max-memory expects a size such as 512M, 2G or 1.5GiB"},
      {build + "--max-memory 0", "got '0'"},
      {"build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "out.map"), "unknown map file extension '.map'"},
      {"build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "no" / "out.umb"), "does not exist"},
      {"info --max-memory -5 " + quoted(dir / "room.xyz"), "--max-memory"},
      {"query " + quoted(dir / "room.xyz") + " line --input - --radius nan",
       "the capsule radius in metres must be a number in [0, 1e+06], got 'nan'"},
      {"query " + quoted(dir / "room.xyz") + " line --input - --radius inf", "got 'inf'"},
      {"query " + quoted(dir / "room.xyz") + " line --input - --radius -1", "got '-1'"},
      {"query " + quoted(dir / "room.xyz") + " sphere --input - --max-memory lots", "--max-memory"},
      {"render " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "x.png") + " --max-memory 0", "--max-memory"},
      {"view " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "x.html") + " --max-memory 1Q", "--max-memory"},
      {"convert " + quoted(dir / "room.xyz") + " " + quoted(dir / "x.umb"), "unknown map file extension '.xyz'"},
  };
  for (const Case& c : cases) {
    const CommandResult result = run(c.arguments);
    EXPECT_EQ(result.exit_code, 2) << c.arguments << "\n" << result.output;
    EXPECT_TRUE(contains(result.output, c.expected)) << c.arguments << "\n" << result.output;
    // One line saying what is wrong, one saying where the help is: not the help itself.
    const std::string command = c.arguments.substr(0, c.arguments.find(' '));
    EXPECT_TRUE(result.output.starts_with("umbra: error: ")) << c.arguments << "\n" << result.output;
    EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 2) << c.arguments << "\n" << result.output;
    EXPECT_TRUE(result.output.ends_with("\nRun `umbra " + command + " --help` for the options.\n"))
        << c.arguments << "\n" << result.output;
    EXPECT_EQ(result.output.find("0000000000000000000000"), std::string::npos) << "a number printed in full";
  }
  EXPECT_FALSE(fs::exists(dir / "out.umb"));
  EXPECT_TRUE(temporaries_in(dir).empty());
}

/// A strict JSON checker (RFC 8259 grammar; no inf, nan or trailing commas).
class JsonChecker {
 public:
  explicit JsonChecker(std::string_view text) : text_(text) {}
  bool valid() {
    const bool ok = value();
    space();
    return ok && at_ == text_.size();
  }

 private:
  void space() {
    while (at_ < text_.size() && (text_[at_] == ' ' || text_[at_] == '\n' || text_[at_] == '\t' || text_[at_] == '\r')) {
      ++at_;
    }
  }
  bool literal(std::string_view word) {
    if (text_.substr(at_, word.size()) != word) return false;
    at_ += word.size();
    return true;
  }
  bool digits() {
    const std::size_t start = at_;
    while (at_ < text_.size() && text_[at_] >= '0' && text_[at_] <= '9') ++at_;
    return at_ > start;
  }
  bool number() {
    literal("-");
    if (!literal("0") && !digits()) return false;
    if (literal(".") && !digits()) return false;
    if (at_ < text_.size() && (text_[at_] == 'e' || text_[at_] == 'E')) {
      ++at_;
      if (!literal("+")) literal("-");
      if (!digits()) return false;
    }
    return true;
  }
  bool string() {
    if (!literal("\"")) return false;
    while (at_ < text_.size() && text_[at_] != '"') at_ += text_[at_] == '\\' ? 2 : 1;
    return literal("\"");
  }
  bool value() {
    space();
    if (at_ >= text_.size()) return false;
    const char c = text_[at_];
    if (c == '{' || c == '[') {
      const char close = c == '{' ? '}' : ']';
      ++at_;
      space();
      if (literal(std::string_view(&close, 1))) return true;
      do {
        if (c == '{') {
          space();
          if (!string()) return false;
          space();
          if (!literal(":")) return false;
        }
        if (!value()) return false;
        space();
      } while (literal(","));
      return literal(std::string_view(&close, 1));
    }
    if (c == '"') return string();
    return literal("true") || literal("false") || literal("null") || number();
  }

  std::string_view text_;
  std::size_t at_ = 0;
};

TEST(ErrorsAndLimits, TheJsonCheckerKnowsJson) {
  EXPECT_TRUE(JsonChecker(R"({"a": [1, -2.5e+3, null], "b": "x"})").valid());
  EXPECT_FALSE(JsonChecker(R"({"a": inf})").valid());
  EXPECT_FALSE(JsonChecker(R"({"a": -nan})").valid());
  EXPECT_FALSE(JsonChecker(R"({"a": 1,})").valid());
}

// info --json is JSON at the extremes of the resolution range too (and
// every map has one in range now).
TEST(ErrorsAndLimits, InfoJsonIsValidJsonAtTheExtremes) {
  const fs::path dir = test::scratch_dir();
  for (const double resolution : {kMinResolution, kMaxResolution}) {
    OccupancyMap map(resolution, 21);
    map.set_log_odds(Vec3d{0.0, 0.0, 0.0}, 2.0f);
    map.set_log_odds(Vec3d{-resolution * 1000, 0.0, 0.0}, -1.0f);
    const fs::path path = dir / ("extreme-" + std::to_string(resolution) + ".umb");
    save_map(map, path);
    CommandResult info = run("info --json " + quoted(path));
    EXPECT_EQ(info.exit_code, 0) << info.output;
    while (!info.output.empty() && info.output.back() == '\n') info.output.pop_back();
    EXPECT_TRUE(JsonChecker(info.output).valid()) << info.output;
    EXPECT_TRUE(contains(info.output, "\"occupied_voxels\": 1")) << info.output;
  }
}

// --- pre-flight ---------------------------------------------------------------------

// A truncated second input is found before the first (a large one) is
// inserted: the program never says "inserting", writes no map, and names the
// input. With --keep-going the bad input is skipped and the rest saved.
TEST(ErrorsAndLimits, PreflightFindsABadLaterInputBeforeInsertingAnything) {
  const fs::path dir = test::scratch_dir();
  const std::vector<Vec3f> points = room_points(200'000);
  write_xyz(dir / "big.xyz", points);
  Scan scan;
  scan.points = room_points(1000);
  write_scan_graph(dir / "whole.graph", {scan, scan});
  std::vector<std::uint8_t> bytes = test::read_bytes(dir / "whole.graph");
  bytes.resize(bytes.size() - 100);
  test::write_bytes(dir / "cut.graph", bytes);

  const std::string inputs = quoted(dir / "big.xyz") + " " + quoted(dir / "cut.graph");
  const CommandResult failed = run("build " + inputs + " -o " + quoted(dir / "map.umb") + " --res 0.05");
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_TRUE(contains(failed.output, "umbra: error: input 2 of 2 (" + (dir / "cut.graph").string() + "): " +
                                          (dir / "cut.graph").string() + ": byte"))
      << failed.output;
  EXPECT_TRUE(contains(failed.output, "truncated")) << failed.output;
  EXPECT_FALSE(contains(failed.output, "inserting")) << "a scan was inserted before the pre-flight failed:\n"
                                                     << failed.output;
  EXPECT_FALSE(fs::exists(dir / "map.umb"));

  const CommandResult kept = run("build " + inputs + " -o " + quoted(dir / "map.umb") + " --res 0.05 --keep-going");
  EXPECT_EQ(kept.exit_code, 3) << kept.output;
  EXPECT_TRUE(contains(kept.output, "umbra: warning: input 2 of 2 (" + (dir / "cut.graph").string() + ")")) << kept.output;
  EXPECT_TRUE(contains(kept.output, "skipping that input (--keep-going)")) << kept.output;
  EXPECT_TRUE(contains(kept.output, "inserting input 1 of 2")) << kept.output;
  EXPECT_FALSE(contains(kept.output, "inserting input 2 of 2")) << kept.output;
  OccupancyMap expected(0.05);
  expected.insert_point_cloud({0, 0, 0}, points);
  EXPECT_EQ(leaves(load_map(dir / "map.umb")), leaves(expected));
}

// A scan whose sensor lies outside the map is found by the pre-flight too,
// named by file and scan; --keep-going skips just that scan.
TEST(ErrorsAndLimits, PreflightNamesTheFileAndScanOfASensorOutsideTheMap) {
  const fs::path dir = test::scratch_dir();
  std::vector<Scan> scans(3);
  for (Scan& scan : scans) scan.points = {{0.3f, 0.2f, 0.1f}, {-0.3f, 0.2f, 0.1f}};
  scans[2].origin = {5.0f, 0.0f, 0.0f};  // a 4-level map at 10 cm spans [-0.8, 0.8)
  write_scan_graph(dir / "three.graph", scans);
  const std::string arguments = "build " + quoted(dir / "three.graph") + " -o " + quoted(dir / "map.umb") +
                                " --res 0.1 --depth-levels 4";
  const CommandResult failed = run(arguments);
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_TRUE(contains(failed.output, "umbra: error: input 1 of 1 (" + (dir / "three.graph").string() +
                                          "), scan 3 of 3: the sensor origin (5, 0, 0) lies outside the map, which "
                                          "spans [-0.8, 0.8) on every axis; raise --depth-levels or --res"))
      << failed.output;
  EXPECT_FALSE(contains(failed.output, "inserting")) << failed.output;
  EXPECT_FALSE(fs::exists(dir / "map.umb"));

  const CommandResult kept = run(arguments + " --keep-going");
  EXPECT_EQ(kept.exit_code, 3) << kept.output;
  EXPECT_TRUE(contains(kept.output, "skipping that scan (--keep-going)")) << kept.output;
  EXPECT_TRUE(contains(kept.output, "total: 2 scans")) << kept.output;
}

// Folders are checked before the inputs are read: a folder that cannot be
// written (as a user without the permission), or an output that is a folder.
TEST(ErrorsAndLimits, PreflightChecksTheOutputCanBeWritten) {
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "room.xyz", room_points(1000));
  fs::create_directories(dir / "folder.umb");
  const CommandResult folder = run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "folder.umb"));
  EXPECT_EQ(folder.exit_code, 1) << folder.output;
  EXPECT_TRUE(contains(folder.output, "cannot save to '" + (dir / "folder.umb").string() + "': it is a folder"))
      << folder.output;
  EXPECT_FALSE(contains(folder.output, "inserting")) << folder.output;

  const fs::path locked = dir / "locked";
  fs::create_directories(locked);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                              fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  fs::permissions(dir, fs::perms::others_exec | fs::perms::others_read, fs::perm_options::add);
  std::string as_user;
  if (::geteuid() == 0) {
    if (test::run_command("setpriv --version").exit_code != 0) GTEST_SKIP() << "root without setpriv: cannot drop permissions";
    as_user = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  }
  const CommandResult denied =
      test::run_command(as_user + cli() + " build " + quoted(dir / "room.xyz") + " -o " + quoted(locked / "map.umb"));
  EXPECT_EQ(denied.exit_code, 1) << denied.output;
  EXPECT_TRUE(contains(denied.output, (locked / "map.umb").string())) << denied.output;
  EXPECT_TRUE(contains(denied.output, "Permission denied")) << denied.output;
  EXPECT_FALSE(contains(denied.output, "inserting")) << denied.output;
}

// What the pre-flight cannot see (a bad line in the middle of a file) is
// reported with the input, the scan and the line.
TEST(ErrorsAndLimits, ALaterFailureNamesTheInputTheScanAndTheLine) {
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "good.xyz", room_points(100));
  test::write_file(dir / "bad.xyz", "1 2 3\n4 five 6\n");
  const CommandResult failed = run("build " + quoted(dir / "good.xyz") + " " + quoted(dir / "bad.xyz") + " -o " +
                                   quoted(dir / "map.umb"));
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_TRUE(contains(failed.output, "umbra: error: input 2 of 2 (" + (dir / "bad.xyz").string() + "), scan 1: " +
                                          (dir / "bad.xyz").string() + ":2: 'five' is not a number"))
      << failed.output;
  EXPECT_FALSE(fs::exists(dir / "map.umb"));
}

// --- memory ------------------------------------------------------------------------------

TEST(ErrorsAndLimits, MaxMemoryRefusesWithTheFileTheNeedAndTheLimit) {
  const fs::path dir = test::scratch_dir();
  OccupancyMap map(0.1);
  map.insert_point_cloud({0, 0, 0}, room_points(20'000));
  save_map(map, dir / "room.umb");
  const CommandResult info = run("info " + quoted(dir / "room.umb") + " --max-memory 16K");
  EXPECT_EQ(info.exit_code, 1) << info.output;
  EXPECT_TRUE(contains(info.output, "umbra: error: " + (dir / "room.umb").string() + ": loading this map (")) << info.output;
  EXPECT_TRUE(contains(info.output, "more than the memory limit of 16.0 KiB (16384 bytes)")) << info.output;
  EXPECT_EQ(run("info " + quoted(dir / "room.umb") + " --max-memory 1G").exit_code, 0);
  EXPECT_EQ(run("convert " + quoted(dir / "room.umb") + " " + quoted(dir / "room.bt") + " --max-memory 16K").exit_code,
            1);
  EXPECT_FALSE(fs::exists(dir / "room.bt"));
  // The commands that only load a map say the same.
  for (const std::string& command : {"query " + quoted(dir / "room.umb") + " nodes --count",
                                     "render " + quoted(dir / "room.umb") + " -o " + quoted(dir / "room.png"),
                                     "view " + quoted(dir / "room.umb") + " -o " + quoted(dir / "room.html")}) {
    const CommandResult refused = run(command + " --max-memory 16K");
    if (contains(refused.output, "built without the browser viewer")) continue;  // `view` needs node and npm
    EXPECT_EQ(refused.exit_code, 1) << command << "\n" << refused.output;
    EXPECT_TRUE(contains(refused.output, (dir / "room.umb").string() + ": loading this map (")) << refused.output;
  }
  EXPECT_FALSE(fs::exists(dir / "room.png"));
  EXPECT_FALSE(fs::exists(dir / "room.html"));
  EXPECT_EQ(run("query " + quoted(dir / "room.umb") + " nodes --count --max-memory 1G").exit_code, 0);

  write_xyz(dir / "room.xyz", room_points(100'000));
  const CommandResult build = run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "m.umb") +
                                  " --max-memory 1M");
  EXPECT_EQ(build.exit_code, 1) << build.output;
  EXPECT_TRUE(contains(build.output, "input 1 of 1 (" + (dir / "room.xyz").string() + "), scan 1: " +
                                         (dir / "room.xyz").string() + ": making room for")) << build.output;
  EXPECT_TRUE(contains(build.output, "more than the memory limit of 1.0 MiB (1048576 bytes)")) << build.output;
}

// --- signals ---------------------------------------------------------------------------

/// Starts the program with `arguments` and UMBRA_TEST_PAUSE_IN_SAVE set; its output goes to `log`.
pid_t start_pausing_build(const std::vector<std::string>& arguments, const fs::path& log) {
  const pid_t child = ::fork();
  if (child != 0) return child;
  ::setenv("UMBRA_TEST_PAUSE_IN_SAVE", "1", 1);
  std::FILE* out = std::fopen(log.c_str(), "w");
  if (out != nullptr) {
    ::dup2(::fileno(out), 1);
    ::dup2(::fileno(out), 2);
  }
  std::vector<char*> argv;
  std::string program = cli();
  argv.push_back(program.data());
  std::vector<std::string> copies = arguments;
  for (std::string& a : copies) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(program.c_str(), argv.data());
  ::_exit(127);
}

/// Waits (at most a minute: a hang detector) until `dir` holds a temporary
/// file with a header in it: the save's (the pre-flight's probe is empty).
bool wait_for_temporary(const fs::path& dir, pid_t child) {
  for (int i = 0; i < 6000; ++i) {
    for (const std::string& name : temporaries_in(dir)) {
      std::error_code ignored;
      if (fs::file_size(dir / name, ignored) > 0) return true;
    }
    int status = 0;
    if (::waitpid(child, &status, WNOHANG) == child) return false;  // it ended without pausing
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

int wait_for(pid_t child) {
  int status = 0;
  ::waitpid(child, &status, 0);
  return status;
}

std::string text_of(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// SIGTERM and SIGINT during a save: the temporary file is removed, the old
// map is untouched, and the program dies of the signal (a shell says 143, 130).
TEST(ErrorsAndLimits, ASignalDuringASaveRemovesTheTemporaryFile) {
  for (const int signal_number : {SIGTERM, SIGINT}) {
    SCOPED_TRACE(signal_number == SIGTERM ? "SIGTERM" : "SIGINT");
    const fs::path dir = test::scratch_dir();
    write_xyz(dir / "room.xyz", room_points(5000));
    OccupancyMap old_map(0.2);
    old_map.insert_point_cloud({0, 0, 0}, room_points(100));
    save_map(old_map, dir / "map.umb");
    const std::vector<std::uint8_t> old_bytes = test::read_bytes(dir / "map.umb");

    const pid_t child = start_pausing_build({"build", (dir / "room.xyz").string(), "-o", (dir / "map.umb").string()},
                                            dir / "log.txt");
    ASSERT_TRUE(wait_for_temporary(dir, child)) << text_of(dir / "log.txt");
    ASSERT_EQ(::kill(child, signal_number), 0);
    const int status = wait_for(child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number) << "status " << status;
    EXPECT_TRUE(temporaries_in(dir).empty()) << temporaries_in(dir).front();
    EXPECT_EQ(test::read_bytes(dir / "map.umb"), old_bytes);
  }
  // Through a shell, the exit status is 128 + the signal's number.
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "room.xyz", room_points(100));
  const CommandResult shell = test::run_command(
      "UMBRA_TEST_PAUSE_IN_SAVE=1 " + cli() + " build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "m.umb") +
      " > /dev/null & pid=$!; until [ -n \"$(find " + quoted(dir) + " -name '.*.tmp-*' -size +0c)\" ]; do sleep 0.01; "
      "done; kill -TERM $pid; wait $pid; echo \"status $?\"");
  EXPECT_TRUE(contains(shell.output, "status 143")) << shell.output;
  EXPECT_TRUE(temporaries_in(dir).empty());
}

// kill -9 cannot be caught: its temporary file stays until the next save to
// the same target removes it. A temporary file whose process still runs is
// left alone.
TEST(ErrorsAndLimits, TheNextSaveRemovesWhatAKilledSaveLeft) {
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "room.xyz", room_points(5000));
  const std::vector<std::string> arguments = {"build", (dir / "room.xyz").string(), "-o", (dir / "map.umb").string()};
  const pid_t child = start_pausing_build(arguments, dir / "log.txt");
  ASSERT_TRUE(wait_for_temporary(dir, child)) << text_of(dir / "log.txt");
  const std::vector<std::string> left = temporaries_in(dir);
  ASSERT_EQ(::kill(child, SIGKILL), 0);
  wait_for(child);
  ASSERT_EQ(temporaries_in(dir), left) << "kill -9 leaves its temporary file";
  // A live process's temporary file (this test's own PID) and another target's.
  const std::string live = ".map.umb.tmp-" + std::to_string(::getpid()) + "-0-1";
  test::write_file(dir / live, "being written");
  const std::string other = ".other.umb.tmp-" + left.front().substr(left.front().find("tmp-") + 4);
  test::write_file(dir / other, "another target's");

  const CommandResult again = run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "map.umb"));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  std::vector<std::string> remaining = temporaries_in(dir);
  std::sort(remaining.begin(), remaining.end());
  std::vector<std::string> expected = {live, other};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(remaining, expected);
  EXPECT_NO_THROW((void)load_map(dir / "map.umb"));
}

// --- symbolic links ------------------------------------------------------------------

// -o on a symbolic link writes the file it points to; the link stays.
TEST(ErrorsAndLimits, OutputThroughASymbolicLinkReplacesItsTarget) {
  const fs::path dir = test::scratch_dir();
  fs::create_directories(dir / "maps");
  write_xyz(dir / "room.xyz", room_points(2000));
  OccupancyMap old_map(0.2);
  save_map(old_map, dir / "maps" / "current.umb");
  fs::create_symlink("maps/current.umb", dir / "latest.umb");
  const CommandResult build = run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "latest.umb"));
  ASSERT_EQ(build.exit_code, 0) << build.output;
  EXPECT_TRUE(fs::is_symlink(dir / "latest.umb"));
  EXPECT_EQ(fs::read_symlink(dir / "latest.umb"), fs::path("maps/current.umb"));
  OccupancyMap expected(0.1);
  expected.insert_point_cloud({0, 0, 0}, room_points(2000));
  EXPECT_EQ(leaves(load_map(dir / "maps" / "current.umb")), leaves(expected));
  EXPECT_TRUE(temporaries_in(dir).empty());
  EXPECT_TRUE(temporaries_in(dir / "maps").empty());
  // convert too, and a link to a file that does not exist yet.
  fs::create_symlink("maps/new.bt", dir / "new.bt");
  const CommandResult convert = run("convert " + quoted(dir / "latest.umb") + " " + quoted(dir / "new.bt"));
  ASSERT_EQ(convert.exit_code, 0) << convert.output;
  EXPECT_TRUE(fs::is_symlink(dir / "new.bt"));
  EXPECT_TRUE(fs::is_regular_file(dir / "maps" / "new.bt"));
}

// --- threads -------------------------------------------------------------------------------

// The issue's reproducer: a process limit lets only a few of the 8 threads
// start. The build finishes on those, says so, and saves the map.
TEST(ErrorsAndLimits, AProcessLimitOnThreadsGivesAWarningNotAHang) {
#if defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "ThreadSanitizer starts threads of its own, which a process limit of a few tasks refuses";
#endif
  if (::geteuid() != 0 || test::run_command("setpriv --version && prlimit --version").exit_code != 0) {
    GTEST_SKIP() << "needs root, setpriv and prlimit to run the program as another user under a process limit";
  }
  const fs::path dir = test::scratch_dir();
  fs::permissions(dir, fs::perms::all);
  write_xyz(dir / "room.xyz", room_points(20'000));
  // A user of this test's own (not nobody: other tests run nobody's
  // processes, and the limit counts all of the user's tasks; ctest -j2 ran
  // two side by side and this one failed): its tasks now, plus the program
  // and two threads.
  const std::string user = "60123";
  const CommandResult count = test::run_command("ps -L -u " + user + " --no-headers 2>/dev/null | wc -l");
  const int allowed = std::atoi(count.output.c_str()) + 3;
  // (LeakSanitizer's exit check needs a thread of its own, which the limit refuses: off for this run.)
  const CommandResult limited = test::run_command(
      "ASAN_OPTIONS=detect_leaks=0 timeout 120 prlimit --nproc=" + std::to_string(allowed) + " setpriv --reuid=" + user + " --regid=" + user + " --clear-groups " +
      cli() + " build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "map.umb") + " --threads 8");
  EXPECT_EQ(limited.exit_code, 0) << limited.output;  // timeout's 124 would mean a hang
  EXPECT_TRUE(contains(limited.output, "umbra: warning: only ")) << limited.output;
  EXPECT_TRUE(contains(limited.output, " of the 8 threads asked for could be started")) << limited.output;
  OccupancyMap expected(0.1);
  expected.insert_point_cloud({0, 0, 0}, room_points(20'000));
  EXPECT_EQ(leaves(load_map(dir / "map.umb")), leaves(expected));
}

// --- TUM warnings ---------------------------------------------------------------------------

TEST(ErrorsAndLimits, BuildShowsTheReadersWarnings) {
  UMBRA_REQUIRE_SHARED_DATA(tum, "tum_fr2_pioneer_slam2");
  const fs::path dir = test::scratch_dir();
  const CommandResult build = run("build " + quoted(tum) + " -o " + quoted(dir / "tum.umb") + " --res 0.2");
  ASSERT_EQ(build.exit_code, 0) << build.output;
  EXPECT_TRUE(contains(build.output, "umbra: warning: my_association.txt: ")) << build.output;
  EXPECT_TRUE(contains(build.output, "rows were skipped because their images are missing (the first is line"))
      << build.output;
  EXPECT_TRUE(contains(build.output, "total: 10 scans")) << build.output;
}

}  // namespace
}  // namespace umbra
