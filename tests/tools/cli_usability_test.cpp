// The `umbra` program as a new user meets it (issue 23, point 5): a missing
// input is an input failure (exit code 1) naming the file, the help states
// the exit codes and the default resolution, `build` writes OctoMap files,
// says which resolution it used, reports progress into a log as the scans
// go, counts "1 thread", keeps its table aligned for long scan names; `query
// --help` lists every kind with its lines and `query` reads standard input
// without --input. Option errors (one line and a pointer to the help) are
// checked case by case in errors_and_limits_test.cpp. The progress bar's
// text (time left) is checked directly.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "progress_bar.hpp"
#include "query_lines.hpp"
#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/scan_graph.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;

using test::cli;
using test::quoted;
using test::contains;
using test::run;

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Points on the walls of a 4 m room around the origin.
std::vector<Vec3f> room_points() {
  std::vector<Vec3f> points;
  for (int i = -19; i <= 19; ++i) {
    for (int j = -19; j <= 19; ++j) {
      const float a = static_cast<float>(i) * 0.1f;
      const float b = static_cast<float>(j) * 0.1f;
      for (const Vec3f p : {Vec3f{2.0f, a, b}, Vec3f{-2.0f, a, b}, Vec3f{a, 2.0f, b}, Vec3f{a, -2.0f, b}}) {
        points.push_back(p);
      }
    }
  }
  return points;
}

void write_xyz(const fs::path& path) {
  std::ofstream out(path);
  for (const Vec3f& p : room_points()) out << p.x << ' ' << p.y << ' ' << p.z << '\n';
}

/// A ScanGraph of `scans` scans of the room from slightly different places.
void write_graph(const fs::path& path, int scans) {
  std::vector<Scan> graph;
  for (int i = 0; i < scans; ++i) {
    Scan scan;
    scan.origin = {0.1f * static_cast<float>(i), 0.0f, 0.0f};
    scan.points = room_points();
    graph.push_back(scan);
  }
  write_scan_graph(path, graph);
}

// --- the progress bar's text ---------------------------------------------------

TEST(ProgressText, SaysTheTimeLeftOnceThereIsARate) {
  using cli::progress_text;
  using cli::time_left_text;
  EXPECT_EQ(time_left_text(0.25, 10.0), "about 30 s left");
  EXPECT_EQ(time_left_text(0.1, 100.0), "about 15 min 00 s left");
  EXPECT_EQ(time_left_text(0.01, 100.0), "about 2 h 45 min left");
  EXPECT_EQ(time_left_text(0.99, 10.0), "under 1 s left");
  EXPECT_EQ(time_left_text(0.5, 0.5), "") << "under a second the rate says too little";
  EXPECT_EQ(time_left_text(0.0, 10.0), "");
  EXPECT_EQ(time_left_text(1.0, 10.0), "");
  EXPECT_EQ(progress_text("building", false, 0.25, 10.0, "3 of 12 scans inserted"),
            "umbra: building:  25% 3 of 12 scans inserted, 10.0 s so far, about 30 s left");
  const std::string bar = progress_text("building", true, 0.5, 4.0, "6 of 12 scans inserted");
  EXPECT_EQ(bar, "building [###############...............]  50% 6 of 12 scans inserted, about 4 s left");
}

// --- exit codes ----------------------------------------------------------------

// A path that is not there is an input failure (exit code 1), as a malformed
// file is, with the file named; --keep-going skips it like any bad input.
TEST(CliUsability, AMissingInputIsAFailureNamingTheFile) {
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "room.xyz");
  ASSERT_EQ(run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "room.umb")).exit_code, 0);
  const std::string missing = quoted(dir / "missing.umb");
  const std::string room = quoted(dir / "room.umb");
  const std::vector<std::string> commands = {
      "build " + quoted(dir / "missing.xyz") + " -o " + quoted(dir / "out.umb"),
      "build " + quoted(dir / "no_such_folder") + " -o " + quoted(dir / "out.umb"),
      "info " + missing,
      "convert " + missing + " " + quoted(dir / "out.bt"),
      "query " + missing + " sphere --input " + quoted(dir / "room.xyz"),
      "query " + room + " sphere --input " + quoted(dir / "missing.txt"),
      "crop " + missing + " -o " + quoted(dir / "out.umb") + " --bbox 0,0,0,1,1,1",
      "compare " + room + " " + missing,
      "merge " + room + " " + missing + " -o " + quoted(dir / "out.umb"),
      "export " + missing + " -o " + quoted(dir / "out.ply"),
      "view " + missing + " -o " + quoted(dir / "out.html"),
  };
  for (const std::string& command : commands) {
    const CommandResult result = run(command);
    EXPECT_EQ(result.exit_code, 1) << command << "\n" << result.output;
    EXPECT_TRUE(contains(result.output, "umbra: error: ")) << command << "\n" << result.output;
    EXPECT_TRUE(contains(result.output, "missing") || contains(result.output, "no_such_folder"))
        << command << "\n" << result.output;
    EXPECT_TRUE(contains(result.output, "No such file or directory")) << command << "\n" << result.output;
  }
  for (const char* name : {"out.umb", "out.bt", "out.ply", "out.html"}) EXPECT_FALSE(fs::exists(dir / name)) << name;

  const CommandResult skipped = run("build " + quoted(dir / "missing.xyz") + " " + quoted(dir / "room.xyz") + " -o " +
                                    quoted(dir / "kept.umb") + " --keep-going");
  EXPECT_EQ(skipped.exit_code, 3) << skipped.output;
  EXPECT_TRUE(contains(skipped.output, "input 1 of 2 (" + (dir / "missing.xyz").string() + "): cannot read"))
      << skipped.output;
  EXPECT_TRUE(fs::exists(dir / "kept.umb"));
}

TEST(CliUsability, HelpAndReadmeStateTheExitCodesAndTheDefaultResolution) {
  const CommandResult help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  for (const char* words : {"Exit codes: 0 success; 1 an input or the system failed (a missing, unreadable or",
                            "2 bad usage", "3 build --keep-going"}) {
    EXPECT_TRUE(contains(help.output, words)) << words << "\n" << help.output;
  }
  const CommandResult build_help = run("build --help");
  EXPECT_TRUE(contains(build_help.output, "voxel edge in metres, 0.0001 to 1000 (default 0.1")) << build_help.output;
  const std::string readme = read_text(test::source_dir() / "README.md");
  EXPECT_TRUE(contains(readme, "`--res R` (voxel edge in metres; default 0.1")) << "README: --res and its default";
  EXPECT_TRUE(contains(readme, "a missing, unreadable or malformed file")) << "README: exit code 1 for a missing file";
}

// --- build ---------------------------------------------------------------------

TEST(CliUsability, BuildSaysWhichResolutionItUsed) {
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "room.xyz");
  const CommandResult by_default = run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "a.umb"));
  ASSERT_EQ(by_default.exit_code, 0) << by_default.output;
  EXPECT_TRUE(by_default.output.starts_with("0.1 m voxels (the default; set it with --res), 16 depth levels"))
      << by_default.output;
  EXPECT_DOUBLE_EQ(load_map(dir / "a.umb").resolution(), 0.1);
  const CommandResult chosen = run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "b.umb") + " --res 0.2");
  ASSERT_EQ(chosen.exit_code, 0) << chosen.output;
  EXPECT_TRUE(chosen.output.starts_with("0.2 m voxels, 16 depth levels")) << chosen.output;
}

// `build -o x.bt` and `-o x.ot` write what `convert` makes of the same map,
// byte for byte; OctoMap's 16 depth levels are checked before any work.
TEST(CliUsability, BuildWritesOctoMapFiles) {
  const fs::path dir = test::scratch_dir();
  write_graph(dir / "room.graph", 2);
  const std::string build = "build " + quoted(dir / "room.graph") + " --res 0.1 -o ";
  ASSERT_EQ(run(build + quoted(dir / "room.umb")).exit_code, 0);
  for (const char* format : {"bt", "ot"}) {
    const fs::path direct = dir / (std::string("direct.") + format);
    const fs::path converted = dir / (std::string("converted.") + format);
    const CommandResult built = run(build + quoted(direct));
    ASSERT_EQ(built.exit_code, 0) << built.output;
    EXPECT_TRUE(contains(built.output, "wrote " + direct.string())) << built.output;
    ASSERT_EQ(run("convert " + quoted(dir / "room.umb") + " " + quoted(converted)).exit_code, 0);
    EXPECT_EQ(test::read_bytes(direct), test::read_bytes(converted)) << format;
  }
  EXPECT_TRUE(contains(run(build + quoted(dir / "direct2.bt")).output, "note: .bt keeps only free / occupied"));
  const CommandResult deep = run(build + quoted(dir / "deep.bt") + " --depth-levels 18");
  EXPECT_EQ(deep.exit_code, 2) << deep.output;
  EXPECT_TRUE(contains(deep.output, "OctoMap files (.bt) hold 16 depth levels, this map has 18")) << deep.output;
  EXPECT_FALSE(fs::exists(dir / "deep.bt"));
}

// With stderr not a terminal (a log, CI), a line per scan comes as the scans
// are inserted: in the merged log it stands before the table, which is
// printed at the end.
TEST(CliUsability, ProgressGoesToALogAsTheScansGo) {
  const fs::path dir = test::scratch_dir();
  write_graph(dir / "three.graph", 3);
  const CommandResult result = test::run_command(cli() + " build " + quoted(dir / "three.graph") + " -o " +
                                                 quoted(dir / "three.umb") + " --res 0.1 > " + quoted(dir / "log") +
                                                 " 2>&1");
  ASSERT_EQ(result.exit_code, 0);
  const std::string log = read_text(dir / "log");
  const auto first = log.find("umbra: building:  33% 1 of 3 scans inserted, ");
  const auto table = log.find("points       rays");
  ASSERT_NE(first, std::string::npos) << log;
  ASSERT_NE(table, std::string::npos) << log;
  EXPECT_LT(first, table) << log;
  EXPECT_TRUE(contains(log, "umbra: building: 100% 3 of 3 scans inserted, ")) << log;
  EXPECT_EQ(log.find('\r'), std::string::npos) << "no terminal control in a log";
}

TEST(CliUsability, OneThreadAndAlignedColumnsForLongScanNames) {
  const fs::path dir = test::scratch_dir();
  const std::string long_name = "rgbd_dataset_freiburg2_pioneer_slam2_depth_1311877813.991479.xyz";
  write_xyz(dir / long_name);
  write_xyz(dir / "a.xyz");
  const CommandResult result = run("build " + quoted(dir / "a.xyz") + " " + quoted(dir / long_name) + " -o " +
                                   quoted(dir / "m.umb") + " --threads 1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(contains(result.output, ", 1 thread\n")) << result.output;
  // Every row of the table ends its "points" column where the heading does.
  const std::vector<std::string> lines = lines_of(result.output);
  const auto heading = std::find_if(lines.begin(), lines.end(), [](const std::string& l) { return l.starts_with("scan "); });
  ASSERT_NE(heading, lines.end()) << result.output;
  const std::size_t points_end = heading->find("points") + 6;
  int rows = 0;
  for (auto row = heading + 1; row != lines.end() && !row->starts_with("total:"); ++row) {
    const std::size_t name_end = row->find(".xyz") + 4;
    ASSERT_NE(name_end, std::string::npos + 4) << *row;
    const std::size_t number_end = row->find_first_of(' ', row->find_first_not_of(' ', name_end));
    EXPECT_EQ(number_end, points_end) << *heading << "\n" << *row;
    ++rows;
  }
  EXPECT_EQ(rows, 2) << result.output;
}

// --- query ---------------------------------------------------------------------

TEST(CliUsability, QueryHelpListsEveryKindWithItsInputAndAnswer) {
  const CommandResult help = run("query --help");
  ASSERT_EQ(help.exit_code, 0);
  for (const cli::LineQuery kind : cli::kLineQueries) {
    const std::string row = std::string(cli::to_string(kind));
    const auto at = help.output.find("\n  " + row + " ");
    ASSERT_NE(at, std::string::npos) << row << "\n" << help.output;
    const std::string line = help.output.substr(at + 1, help.output.find('\n', at + 1) - at - 1);
    EXPECT_TRUE(contains(line, cli::layout_of(kind))) << line;
    EXPECT_TRUE(contains(line, std::string("-> ") + cli::answer_of(kind))) << line;
  }
  EXPECT_TRUE(contains(help.output, "'x y z size state' per node")) << help.output;
  EXPECT_TRUE(contains(help.output, "from standard input when --input is not given")) << help.output;
}

TEST(CliUsability, QueryReadsStandardInputWithoutInput) {
  const fs::path dir = test::scratch_dir();
  write_xyz(dir / "room.xyz");
  ASSERT_EQ(run("build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "room.umb")).exit_code, 0);
  {
    std::ofstream lines(dir / "spheres.txt");
    lines << "1 0 0 0.1\n2 0 0 0.3\n0 0 5 0.1\n";  // free space, a wall, unknown space above the room
  }
  const std::string query = cli() + " query " + quoted(dir / "room.umb") + " sphere";
  // stdout only: the timing on stderr differs from run to run.
  const auto answers = [](const std::string& command) { return test::run_command("( ( " + command + " ) 2> /dev/null )"); };
  const CommandResult from_file = answers(query + " --input " + quoted(dir / "spheres.txt"));
  const CommandResult from_pipe = answers("cat " + quoted(dir / "spheres.txt") + " | " + query);
  const CommandResult from_redirect = answers(query + " < " + quoted(dir / "spheres.txt"));
  ASSERT_EQ(from_file.exit_code, 0) << from_file.output;
  EXPECT_EQ(from_file.output, "0\n1\n1\n");
  EXPECT_EQ(from_pipe.exit_code, 0);
  EXPECT_EQ(from_pipe.output, from_file.output);
  EXPECT_EQ(from_redirect.exit_code, 0);
  EXPECT_EQ(from_redirect.output, from_file.output);
  // On a terminal the program would wait for a user who forgot --input: it says so instead.
  if (test::run_command("script --version").exit_code != 0) GTEST_SKIP() << "needs script(1) for a terminal";
  const CommandResult terminal = test::run_command("script -qec \"" + query + "\" /dev/null < /dev/null");
  EXPECT_EQ(terminal.exit_code, 2) << terminal.output;
  EXPECT_TRUE(contains(terminal.output, "query sphere reads one query per line (x y z r) from --input FILE"))
      << terminal.output;
}

}  // namespace
}  // namespace umbra
