// Checks against the memory limit (umbra/core/memory_limit.hpp), for the
// readers and loaders: compare a need with the limit before allocating, and
// turn a std::bad_alloc into a MemoryLimitError that names the file.
// Cost: one atomic load per check. Private to umbra.
#pragma once

#include <cstdint>
#include <new>
#include <string>
#include <utility>

#include "umbra/core/memory_limit.hpp"

namespace umbra::detail {

/// "1.3 GiB (1395864371 bytes)"; below 1 KiB just "512 bytes".
std::string byte_text(std::uint64_t bytes);

/// Throws MemoryLimitError "FILE: WHAT needs NEED, more than the memory limit
/// of LIMIT (...how to raise it)" when `bytes` is above memory_limit().
void require_memory(const std::string& file, const std::string& what, std::uint64_t bytes);

/// MemoryLimitError "FILE: out of memory while WHAT (about NEED)" for a
/// std::bad_alloc; `bytes` 0 leaves the size out.
[[noreturn]] void throw_out_of_memory(const std::string& file, const std::string& what, std::uint64_t bytes);

/// Runs fn(); a plain std::bad_alloc from it becomes throw_out_of_memory(file, what, bytes)
/// (a MemoryLimitError passes unchanged).
template <typename Fn>
decltype(auto) naming_bad_alloc(const std::string& file, const std::string& what, std::uint64_t bytes, Fn&& fn) {
  try {
    return std::forward<Fn>(fn)();
  } catch (const MemoryLimitError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw_out_of_memory(file, what, bytes);
  }
}

}  // namespace umbra::detail
