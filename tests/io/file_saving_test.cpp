// How saves behave around faults (umbra/io/file_saving.hpp), for every
// program that uses the library, not just the umbra CLI: a signal handler's
// clean-up, stale temporary files of dead processes, symbolic links, and the
// pre-flight check. Signals are sent inside a child process, at a known
// moment of the save (the test-only fault hook), so nothing here is timed.
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <fcntl.h>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_support.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/octomap_files.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

OccupancyMap small_map(float value) {
  OccupancyMap map(0.1);
  map.set_log_odds(Vec3d{0.05, 0.05, 0.05}, value);
  return map;
}

void on_signal(int signal_number) {
  remove_unfinished_saves();
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

// A program's SIGTERM handler that calls remove_unfinished_saves() leaves no
// temporary file, whatever the format, and the old file stays as it was.
TEST(FileSaving, ASignalHandlerRemovesTheUnfinishedSave) {
  for (const std::string name : {"map.umb", "map.bt", "map.ot"}) {
    SCOPED_TRACE(name);
    const fs::path dir = test::scratch_dir();
    const fs::path path = dir / name;
    const auto save = [&](const OccupancyMap& map) {
      if (name.ends_with(".umb")) {
        save_map(map, path);
      } else {
        save_octomap(map, path, name.ends_with(".bt") ? OctoMapFormat::bt : OctoMapFormat::ot);
      }
    };
    save(small_map(1.0f));
    const std::vector<std::uint8_t> old_bytes = test::read_bytes(path);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      struct sigaction action {};
      action.sa_handler = on_signal;
      ::sigaction(SIGTERM, &action, nullptr);
      detail::set_map_file_fault_for_testing([] { ::raise(SIGTERM); });  // after the header is written
      try {
        save(small_map(-1.0f));
      } catch (...) {
      }
      ::_exit(0);  // not reached: the signal ends the process
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << "status " << status;
    EXPECT_EQ(names_in(dir), std::vector<std::string>{name});
    EXPECT_EQ(test::read_bytes(path), old_bytes);
  }
}

/// The PID of a process that has ended.
pid_t dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  return child;
}

// A save removes the temporary files of its own target whose process is gone
// and whose lock is free, and nothing else.
TEST(FileSaving, ASaveRemovesOnlyStaleTemporaryFilesOfItsTarget) {
  const fs::path dir = test::scratch_dir();
  const std::string dead = std::to_string(dead_pid());
  const std::string stale = ".map.umb.tmp-" + dead + "-3-12345";
  const std::string live = ".map.umb.tmp-" + std::to_string(::getpid()) + "-7-1";
  const std::string locked = ".map.umb.tmp-" + dead + "-4-999";   // a writer in another PID namespace holds it
  const std::string other = ".other.umb.tmp-" + dead + "-3-12345";  // another target's
  const std::string unlike = ".map.umb.tmp-notapid";
  for (const std::string& name : {stale, live, locked, other, unlike}) test::write_file(dir / name, "partial");
  const int lock_fd = ::open((dir / locked).c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(lock_fd, 0);
  ASSERT_EQ(::flock(lock_fd, LOCK_EX), 0);

  save_map(small_map(1.0f), dir / "map.umb");
  ::close(lock_fd);
  std::vector<std::string> expected = {"map.umb", live, locked, other, unlike};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(names_in(dir), expected);
}

// Saving to a symbolic link replaces the file it points to (through a chain
// of links, and creating it when it does not exist); the links stay.
TEST(FileSaving, SavesGoThroughSymbolicLinks) {
  const fs::path dir = test::scratch_dir();
  fs::create_directories(dir / "store");
  save_map(small_map(1.0f), dir / "store" / "v1.umb");
  fs::create_symlink("store/v1.umb", dir / "current.umb");
  fs::create_symlink(dir / "current.umb", dir / "latest.umb");  // absolute, to another link
  save_map(small_map(-1.0f), dir / "latest.umb");
  EXPECT_TRUE(fs::is_symlink(dir / "latest.umb"));
  EXPECT_TRUE(fs::is_symlink(dir / "current.umb"));
  EXPECT_EQ(load_map(dir / "store" / "v1.umb").log_odds({0.05, 0.05, 0.05}), -1.0f);
  EXPECT_EQ(names_in(dir / "store"), std::vector<std::string>{"v1.umb"});

  fs::create_symlink("store/v2.umb", dir / "next.umb");  // dangling
  save_octomap(small_map(1.0f), dir / "next.umb", OctoMapFormat::ot);
  EXPECT_TRUE(fs::is_symlink(dir / "next.umb"));
  EXPECT_TRUE(fs::is_regular_file(dir / "store" / "v2.umb"));

  fs::create_symlink("loop_b.umb", dir / "loop_a.umb");
  fs::create_symlink("loop_a.umb", dir / "loop_b.umb");
  try {
    save_map(small_map(1.0f), dir / "loop_a.umb");
    ADD_FAILURE() << "a loop of links was saved to";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), "too many levels of symbolic links")) << e.what();
  }
}

TEST(FileSaving, CheckCanSaveSaysWhyNotAndLeavesNothing) {
  const fs::path dir = test::scratch_dir();
  EXPECT_NO_THROW(check_can_save(dir / "map.umb"));
  EXPECT_TRUE(names_in(dir).empty());
  fs::create_directories(dir / "folder.umb");
  try {
    check_can_save(dir / "folder.umb");
    ADD_FAILURE() << "a folder passed";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), "cannot save to '" + (dir / "folder.umb").string() + "': it is a folder")) << e.what();
  }
  try {
    check_can_save(dir / "missing" / "map.umb");
    ADD_FAILURE() << "a missing folder passed";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), (dir / "missing" / "map.umb").string())) << e.what();
    EXPECT_TRUE(contains(e.what(), "No such file or directory")) << e.what();
  }
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"folder.umb"});
}

}  // namespace
}  // namespace umbra
