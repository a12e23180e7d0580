#include <cstdint>
#include <cstdlib>
#include <new>

#include "tree/group_pool.hpp"

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace umbra::detail {

void* HugePageChunks::carve(std::size_t bytes) {
  constexpr std::size_t kAlignment = 64;
  bytes = (bytes + kAlignment - 1) / kAlignment * kAlignment;
  UMBRA_ASSERT(bytes <= kChunkBytes);
  if (kChunkBytes - used_ < bytes) {
    chunks_.reserve(chunks_.size() + 1);  // so that push_back cannot throw with the chunk unowned
    void* chunk = std::aligned_alloc(kChunkBytes, kChunkBytes);
    if (chunk == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    // A hint: without transparent huge pages it fails and nothing changes.
    (void)madvise(chunk, kChunkBytes, MADV_HUGEPAGE);
#endif
    chunks_.emplace_back(chunk);
    used_ = 0;
  }
  void* block = static_cast<char*>(chunks_.back().get()) + used_;
  used_ += bytes;
  return block;
}

void populate(void* memory, std::size_t bytes) {
#if defined(__linux__)
#if !defined(MADV_POPULATE_WRITE)
  constexpr int MADV_POPULATE_WRITE = 23;  // older headers; an older kernel refuses it (EINVAL)
#endif
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto begin = (reinterpret_cast<std::uintptr_t>(memory) + page - 1) / page * page;
  const auto end = (reinterpret_cast<std::uintptr_t>(memory) + bytes) / page * page;
  if (end > begin) (void)madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE);
#else
  (void)memory;
  (void)bytes;
#endif
}

void HugePageChunks::Free::operator()(void* chunk) const { std::free(chunk); }

}  // namespace umbra::detail
