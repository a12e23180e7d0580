// `umbra query --input -` answering as lines arrive, in bounded memory: a
// writer that sends one line and waits for its answer before the next gets
// every answer (equal to the library's), bad lines reported in order and
// the timing counted as before (reading everything first would wait here
// forever: ctest's TIMEOUT is the bound); half a million lines through a
// pipe raise the program's peak memory (ru_maxrss from wait4) by less than
// 16 MiB over a thousand lines, where holding the lines took about 200
// bytes each (not under a sanitizer, whose own memory would dominate); a
// line of 10 MB without a newline is refused by number and the next line
// answered.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "support/query_oracle.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"

extern char** environ;

// Under a sanitizer the program's peak memory is mostly the sanitizer's
// (shadow memory, AddressSanitizer's quarantine of freed blocks).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define UMBRA_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define UMBRA_SANITIZED 1
#endif
#endif

namespace umbra {
namespace {

/// `umbra query MAP KIND --input -` with a pipe for its standard input, its
/// standard output a pipe (or a file) and its standard error a file.
class QueryProcess {
 public:
  QueryProcess(const std::filesystem::path& map, const std::string& kind, const std::filesystem::path& err,
               const std::filesystem::path& out = {}) {
    ::signal(SIGPIPE, SIG_IGN);  // a program that died makes write() fail (EPIPE) instead of ending the test
    int in_pipe[2];
    int out_pipe[2] = {-1, -1};
    EXPECT_EQ(::pipe2(in_pipe, O_CLOEXEC), 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in_pipe[0], 0);
    if (out.empty()) {
      EXPECT_EQ(::pipe2(out_pipe, O_CLOEXEC), 0);
      posix_spawn_file_actions_adddup2(&actions, out_pipe[1], 1);
    } else {
      posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    }
    posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const std::string program = UMBRA_CLI_PATH;
    std::vector<std::string> args = {program, "query", map.string(), kind, "--input", "-"};
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    EXPECT_EQ(::posix_spawn(&pid_, program.c_str(), &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    ::close(in_pipe[0]);
    in_ = in_pipe[1];
    if (out_pipe[1] >= 0) ::close(out_pipe[1]);
    out_ = out_pipe[0];
  }
  ~QueryProcess() {
    close_input();
    if (out_ >= 0) ::close(out_);
    if (pid_ > 0) finish();
  }
  QueryProcess(const QueryProcess&) = delete;
  QueryProcess& operator=(const QueryProcess&) = delete;

  void write(const std::string& bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(in_, bytes.data() + done, bytes.size() - done);
      ASSERT_GT(n, 0) << "umbra query stopped reading";
      done += static_cast<std::size_t>(n);
    }
  }
  /// One line of its output (blocks until it comes; "" at the end).
  std::string read_line() {
    std::string line;
    char c = 0;
    while (::read(out_, &c, 1) == 1 && c != '\n') line += c;
    return line;
  }
  void close_input() {
    if (in_ >= 0) ::close(in_);
    in_ = -1;
  }
  struct Ending {
    int exit_code = -1;
    long peak_kib = 0;  ///< ru_maxrss
  };
  Ending finish() {
    close_input();
    int status = 0;
    rusage usage{};
    Ending ending;
    if (::wait4(pid_, &status, 0, &usage) == pid_) {
      ending.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      ending.peak_kib = usage.ru_maxrss;
    }
    pid_ = -1;
    return ending;
  }

 private:
  pid_t pid_ = -1;
  int in_ = -1;
  int out_ = -1;
};

std::vector<std::string> lines_of(const std::filesystem::path& path) {
  std::vector<std::string> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

class QueryStream : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::scratch_dir();
    test::RandomMapSpec spec;
    spec.depth_levels = 6;
    spec.seed = 8;
    spec.block_fill = 0.3;
    map_ = std::make_unique<OccupancyMap>(test::random_map(spec));
    save_map(*map_, dir_ / "map.umb");
  }
  std::string sphere_answer(double x, double y, double z, double r) const {
    return map_->is_free(Sphere{{x, y, z}, r}).free ? "0" : "1";
  }

  std::filesystem::path dir_;
  std::unique_ptr<OccupancyMap> map_;
};

TEST_F(QueryStream, EachLineIsAnsweredWhileItsWriterWaits) {
  QueryProcess query(dir_ / "map.umb", "sphere", dir_ / "err.txt");
  const double h = map_->grid().half_extent() * 0.8;
  std::size_t answered = 0;
  for (int i = 0; i < 12; ++i) {
    // Numbers written with 6 decimals: the library's answer is for the values the program reads.
    const double x = std::stod(std::to_string(-h + 2 * h * i / 11.0));
    const double y = std::stod(std::to_string(-x / 2));
    const double r = 0.05 + 0.1 * (i % 4);
    if (i == 4) query.write("# a comment, then a bad line\n0.1 0.2 three 0.4\n");
    query.write(std::to_string(x) + " " + std::to_string(y) + " 0.1 " + std::to_string(r) + "\n");
    // The answer comes while this process still holds the pipe open.
    EXPECT_EQ(query.read_line(), sphere_answer(x, y, 0.1, std::stod(std::to_string(r)))) << "line for x = " << x;
    ++answered;
  }
  const QueryProcess::Ending ending = query.finish();
  EXPECT_EQ(ending.exit_code, 1);  // the bad line
  const std::vector<std::string> err = lines_of(dir_ / "err.txt");
  ASSERT_EQ(err.size(), 2u);
  EXPECT_EQ(err[0], "umbra: standard input line 6: 'three' is not a finite number");
  EXPECT_TRUE(std::regex_match(err[1], std::regex("^\\{\"kind\": \"sphere\", \"queries\": " + std::to_string(answered) +
                                                  ", \"seconds\": [0-9.e+-]+, \"us_per_query\": [0-9.e+-]+\\}$")))
      << err[1];
}

TEST_F(QueryStream, HalfAMillionLinesNeedNoMoreMemoryThanAThousand) {
#if defined(UMBRA_SANITIZED)
  GTEST_SKIP() << "a sanitized program's peak memory is mostly the sanitizer's";
#endif
  const std::vector<std::string> lines = {"0.1 0.2 0.3 0.4\n", "-0.5 0.5 0.2 0.1\n", "0.3 -0.6 0.1 0.05\n"};
  const std::vector<std::string> answers = {sphere_answer(0.1, 0.2, 0.3, 0.4), sphere_answer(-0.5, 0.5, 0.2, 0.1),
                                            sphere_answer(0.3, -0.6, 0.1, 0.05)};
  auto run = [&](std::size_t count) {
    QueryProcess query(dir_ / "map.umb", "sphere", dir_ / "err.txt", dir_ / "out.txt");
    std::string chunk;
    for (std::size_t i = 0; i < count; ++i) {
      chunk += lines[i % 3];
      if (chunk.size() > 60000 || i + 1 == count) {
        query.write(chunk);
        chunk.clear();
      }
    }
    const QueryProcess::Ending ending = query.finish();
    EXPECT_EQ(ending.exit_code, 0);
    const std::vector<std::string> out = lines_of(dir_ / "out.txt");
    EXPECT_EQ(out.size(), count);
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (out[i] != answers[i % 3]) {
        ADD_FAILURE() << "answer " << i << " is " << out[i] << ", the library says " << answers[i % 3];
        break;
      }
    }
    return ending.peak_kib;
  };
  const long few = run(1000);
  const long many = run(500'000);
  EXPECT_LT(many - few, 16 * 1024) << "peak memory: " << few << " KiB for 1000 lines, " << many
                                   << " KiB for 500,000";
}

TEST_F(QueryStream, AnEndlessLineIsRefusedByNumberAndTheNextOneAnswered) {
  QueryProcess query(dir_ / "map.umb", "sphere", dir_ / "err.txt");
  query.write("0.1 0.2 0.3 0.4\n");
  EXPECT_EQ(query.read_line(), sphere_answer(0.1, 0.2, 0.3, 0.4));
  const std::string endless(10'000'000, '7');
  query.write(endless + "\n-0.5 0.5 0.2 0.1\n");
  EXPECT_EQ(query.read_line(), sphere_answer(-0.5, 0.5, 0.2, 0.1));
  EXPECT_EQ(query.finish().exit_code, 1);
  const std::vector<std::string> err = lines_of(dir_ / "err.txt");
  ASSERT_FALSE(err.empty());
  EXPECT_EQ(err[0], "umbra: standard input line 2: the line holds 10000000 bytes, more than the 65536 a query line "
                    "may hold");
}

}  // namespace
}  // namespace umbra
