// ChangeJournal: which parts of a map may have changed, scan after scan, for
// the structures derived from the map (the distance field) that bring
// themselves up to date only where the map changed.
//
// An entry is a node (Morton code of its first voxel, depth): some voxel in
// it may have changed state. Entries are coarse on purpose: a scan's entries
// are the nodes of depth >= kJournalDepth its update batch touched (a node
// cleared whole is one entry), so recording costs a walk over the batch's
// coarse groups, not over its voxels. Changes that touch everything
// (thresholds, sensor model, clear, loading) record "everything" instead.
//
// Only a journal with a subscriber records: a map without a distance field
// pays one atomic load per scan. A subscriber remembers the version it has
// seen and asks for the entries since; it gets "everything" when it lags
// behind what the journal kept (entries are dropped beyond kMaxEntries).
//
// Written by the map's writer with the gate closed and read under the map's
// read gate, so the journal and the tree always agree for a reader.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace umbra {
class UpdateBatch;
}

namespace umbra::detail {

class ChangeJournal {
 public:
  struct Entry {
    std::uint64_t code = 0;  ///< first finest voxel of the node
    int depth = 0;
  };
  /// Coarsest granularity of a scan's entries (a node of 8^3 voxels).
  static constexpr int kJournalDepth = 3;
  static constexpr std::size_t kMaxEntries = std::size_t{1} << 20;

  void subscribe() { subscribers_.fetch_add(1, std::memory_order_relaxed); }
  void unsubscribe() { subscribers_.fetch_sub(1, std::memory_order_relaxed); }
  [[nodiscard]] bool active() const { return subscribers_.load(std::memory_order_relaxed) > 0; }

  // Writer side (map's writer, gate closed).
  void record(std::uint64_t code, int depth);
  /// The nodes a scan's batch touches (before it is applied).
  void record_batch(const UpdateBatch& batch);
  void record_everything();

  // Reader side (map's read gate held).
  [[nodiscard]] std::uint64_t version() const { return first_version_ + entries_.size(); }
  /// Appends the entries recorded after `version` to `out`; false when the
  /// journal cannot say (everything changed since, or entries were dropped):
  /// then the subscriber starts over.
  bool changes_since(std::uint64_t version, std::vector<Entry>& out) const;
  [[nodiscard]] std::size_t memory_bytes() const { return entries_.capacity() * sizeof(Entry); }

 private:
  void drop_entries();

  std::atomic<int> subscribers_{0};
  std::vector<Entry> entries_;
  std::uint64_t first_version_ = 0;       // version of entries_[0]
  std::uint64_t everything_version_ = 0;  // "everything changed" at this version
};

}  // namespace umbra::detail
