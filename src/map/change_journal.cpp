#include "map/change_journal.hpp"

#include "tree/update_batch.hpp"

namespace umbra::detail {
namespace {

/// Records the touched nodes below group `group` at `depth` (its eight nodes
/// are of that depth): a node missed whole is one entry, a node with marks
/// below is one entry at kJournalDepth, or is descended into above it.
void record_group(ChangeJournal& journal, const UpdateBatch& batch, int depth, std::uint32_t group,
                  std::uint64_t first_code) {
  const UpdateBatch::Inner& inner = batch.inner(depth, group);
  for (unsigned slot = 0; slot < 8; ++slot) {
    const std::uint64_t code = first_code | (std::uint64_t{slot} << (3 * depth));
    const bool full = (inner.full >> slot & 1u) != 0;
    const std::uint32_t child = inner.child[slot];
    if (full) {
      journal.record(code, depth);
    } else if (child != kNoGroup) {
      if (depth <= ChangeJournal::kJournalDepth) {
        journal.record(code, depth);
      } else {
        record_group(journal, batch, depth - 1, child, code);
      }
    }
  }
}

}  // namespace

void ChangeJournal::record(std::uint64_t code, int depth) {
  if (!active()) return;
  if (entries_.size() >= kMaxEntries) drop_entries();
  entries_.push_back({code, depth});
}

void ChangeJournal::record_batch(const UpdateBatch& batch) {
  if (!active() || batch.empty()) return;
  const int levels = batch.depth_levels();
  if (levels <= ChangeJournal::kJournalDepth) {
    record(0, levels);  // a tiny map: the whole of it
    return;
  }
  record_group(*this, batch, levels, 0, 0);
}

void ChangeJournal::record_everything() {
  // One version further, so that a subscriber up to date until now lags.
  first_version_ += entries_.size() + 1;
  entries_.clear();
  everything_version_ = first_version_;
}

void ChangeJournal::drop_entries() {
  // A subscriber up to date keeps going; one that lags starts over.
  first_version_ += entries_.size();
  entries_.clear();
}

bool ChangeJournal::changes_since(std::uint64_t seen, std::vector<Entry>& out) const {
  if (seen < everything_version_ || seen < first_version_) return false;
  if (seen > version()) return false;  // a journal of another map: start over
  out.insert(out.end(), entries_.begin() + static_cast<std::ptrdiff_t>(seen - first_version_), entries_.end());
  return true;
}

}  // namespace umbra::detail
