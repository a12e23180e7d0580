#include <cstdlib>
#include <new>

#include "tree/group_pool.hpp"

#if defined(__linux__)
#include <sys/mman.h>
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

void HugePageChunks::Free::operator()(void* chunk) const { std::free(chunk); }

}  // namespace umbra::detail
