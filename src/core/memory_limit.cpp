// The memory limit (umbra/core/memory_limit.hpp) and the checks against it
// (core/memory_budget.hpp).
//
// The default is computed once, when the library is loaded: half of the smallest of the
// physical memory, RLIMIT_AS, RLIMIT_DATA and the cgroup memory limit (v2
// memory.max, v1 memory.limit_in_bytes, as the process's cgroup namespace
// shows them), at least 64 MiB.
#include "umbra/core/memory_limit.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/memory_budget.hpp"

namespace umbra {
namespace {

constexpr std::uint64_t kMinimumDefault = std::uint64_t{64} << 20;

std::atomic<std::uint64_t> g_limit{0};  // 0: the default

/// The number in a cgroup limit file, or nothing ("max", missing file).
std::uint64_t cgroup_limit(const char* path) {
  std::ifstream in(path);
  std::uint64_t value = 0;
  if (in >> value && value > 0) return value;
  return UINT64_MAX;
}

std::uint64_t rlimit_of(int resource) {
  rlimit limit{};
  if (::getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return UINT64_MAX;
  return limit.rlim_cur;
}

std::uint64_t compute_default() {
  std::uint64_t available = UINT64_MAX;
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_bytes = ::sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page_bytes > 0) available = std::uint64_t(pages) * std::uint64_t(page_bytes);
  available = std::min({available, rlimit_of(RLIMIT_AS), rlimit_of(RLIMIT_DATA),
                        cgroup_limit("/sys/fs/cgroup/memory.max"),
                        cgroup_limit("/sys/fs/cgroup/memory/memory.limit_in_bytes")});
  return std::max(available / 2, kMinimumDefault);
}

// Worked out when the library is loaded, so that it does not depend on which
// thread first asks and what limits that thread had set meanwhile.
const std::uint64_t g_default_limit = compute_default();

}  // namespace

std::uint64_t default_memory_limit() { return g_default_limit; }

std::uint64_t memory_limit() {
  const std::uint64_t set = g_limit.load(std::memory_order_relaxed);
  return set != 0 ? set : default_memory_limit();
}

void set_memory_limit(std::uint64_t bytes) { g_limit.store(bytes, std::memory_order_relaxed); }

namespace detail {

std::string byte_text(std::uint64_t bytes) {
  if (bytes < 1024) return std::to_string(bytes) + " bytes";
  const char* units[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double value = static_cast<double>(bytes) / 1024.0;
  int unit = 0;
  while (value >= 1024.0 && unit < 5) {
    value /= 1024.0;
    ++unit;
  }
  char text[64];
  std::snprintf(text, sizeof text, "%.1f %s", value, units[unit]);
  return std::string(text) + " (" + std::to_string(bytes) + " bytes)";
}

void require_memory(const std::string& file, const std::string& what, std::uint64_t bytes) {
  const std::uint64_t limit = memory_limit();
  if (bytes <= limit) return;
  throw MemoryLimitError(file + ": " + what + " needs " + byte_text(bytes) + ", more than the memory limit of " +
                         byte_text(limit) +
                         " (if the machine has the memory, raise the limit: umbra --max-memory, "
                         "umbra::set_memory_limit)");
}

void throw_out_of_memory(const std::string& file, const std::string& what, std::uint64_t bytes) {
  throw MemoryLimitError(file + ": out of memory while " + what +
                         (bytes > 0 ? " (it needs about " + byte_text(bytes) + ")" : std::string()));
}

}  // namespace detail
}  // namespace umbra
