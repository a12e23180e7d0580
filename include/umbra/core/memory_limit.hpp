// The memory limit: the most memory umbra lets one file or one scan ask for.
//
// Loading a map (.umb, .bt, .ot) works out from its header (and, for .ot,
// one pass over its node records) how many bytes the tree will take before
// allocating any of it; reading a scan works out what its points take (from
// the count the header declares, or as the points arrive when the format has
// no count; 12 bytes a point, 15 with color; a depth image 20 bytes a
// pixel). A need above the limit throws MemoryLimitError naming the file,
// the need and the limit, and nothing more is allocated. The limit applies
// to each file or scan on its own, not to the sum of everything the program
// holds. A std::bad_alloc that happens anyway while a map is loaded or a
// scan is read comes out as a MemoryLimitError naming the file and the size.
//
// Default: half of the physical memory, or half of the process's own limit
// when that is lower (address space and data segment rlimits, the cgroup's
// memory.max), so that a bomb is refused with a message rather than ending
// in the kernel's out-of-memory killer. Cost: reading the limit is one atomic
// load; the default is worked out once.
// Thread safety: every function may be called from any thread at any time.
#pragma once

#include <cstdint>
#include <new>
#include <stdexcept>
#include <string>

namespace umbra {

/// An allocation umbra refused (beyond memory_limit()) or that failed, with
/// a message naming what was being read and how much it needed. It is a
/// std::bad_alloc, so code that handles running out of memory handles it.
class MemoryLimitError : public std::bad_alloc {
 public:
  explicit MemoryLimitError(const std::string& message) : message_(message) {}
  [[nodiscard]] const char* what() const noexcept override { return message_.what(); }

 private:
  std::runtime_error message_;  // a reference-counted string: copying never throws
};

/// The limit in force, in bytes.
[[nodiscard]] std::uint64_t memory_limit();
/// Sets the limit; 0 restores the default.
void set_memory_limit(std::uint64_t bytes);
/// The default limit (see the file comment), in bytes, at least 64 MiB.
[[nodiscard]] std::uint64_t default_memory_limit();

}  // namespace umbra
