// CellCodes: how a stored brick holds its cells' nearest sites.
//
// A cell's nearest site is an offset in cells within the field's cap
// (field_layout.hpp). Where the offsets within the cap number fewer than
// 2^16 (max_distance up to about 24 cell edges: 63,413 offsets at 24,
// 71,831 at 25), each is stored as a 16-bit code into a table of those offsets,
// 4 bytes a cell for both kinds (dynamicEDT3D keeps 25 bytes a voxel; three
// int8 per kind, 6 bytes a cell, were 31% of that on a map whose box is
// mostly known space). Wider windows keep the three int8 per kind. The
// update works on decoded BrickOffsets; only stored bricks are coded, and a
// query decodes its one cell (a load from the table, 256 KB, mostly in
// cache).
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "core/assert.hpp"
#include "field/distance_transform.hpp"
#include "field/field_layout.hpp"

namespace umbra::detail {

class CellCodes {
 public:
  static constexpr std::uint16_t kNoneCode = 0xFFFF;

  explicit CellCodes(const FieldLayout& layout) : window_(layout.window()), side_(2 * layout.window() + 1) {
    // Count first: a wide window's table of codes would not fit 16 bits.
    std::size_t count = 0;
    const int w = window_;
    for (int z = -w; z <= w && count < kNoneCode; ++z) {
      for (int y = -w; y <= w; ++y) {
        for (int x = -w; x <= w; ++x) {
          if (layout.within_cap(layout.squared(SiteOffset{std::int8_t(x), std::int8_t(y), std::int8_t(z)}))) ++count;
        }
      }
    }
    compact_ = count < kNoneCode;
    if (!compact_) return;
    offset_of_.assign(std::size_t{kNoneCode} + 1, SiteOffset{});  // kNoneCode decodes to none
    code_of_.assign(std::size_t(side_) * side_ * side_, kNoneCode);
    std::uint16_t next = 0;
    for (int z = -w; z <= w; ++z) {
      for (int y = -w; y <= w; ++y) {
        for (int x = -w; x <= w; ++x) {
          const SiteOffset o{std::int8_t(x), std::int8_t(y), std::int8_t(z)};
          if (!layout.within_cap(layout.squared(o))) continue;
          offset_of_[next] = o;
          code_of_[index(o)] = next++;
        }
      }
    }
  }

  /// 2 bytes a site offset (else 3).
  [[nodiscard]] bool compact() const { return compact_; }
  [[nodiscard]] std::size_t bytes_per_cell() const { return compact_ ? 4 : sizeof(CellSites); }
  [[nodiscard]] std::size_t bytes_per_brick() const { return bytes_per_cell() * kBrickVolume; }

  void encode(const BrickOffsets& offsets, unsigned char* cells) const {
    if (!compact_) {
      std::memcpy(cells, offsets.data(), sizeof(BrickOffsets));
      return;
    }
    for (int i = 0; i < kBrickVolume; ++i) {
      const std::uint16_t codes[2] = {code(offsets[std::size_t(i)].occupied), code(offsets[std::size_t(i)].unknown)};
      std::memcpy(cells + 4 * i, codes, 4);
    }
  }
  void decode(const unsigned char* cells, BrickOffsets& offsets) const {
    if (!compact_) {
      std::memcpy(offsets.data(), cells, sizeof(BrickOffsets));
      return;
    }
    for (int i = 0; i < kBrickVolume; ++i) offsets[std::size_t(i)] = cell(cells, i);
  }
  /// One cell of a coded brick.
  [[nodiscard]] CellSites cell(const unsigned char* cells, int i) const {
    if (!compact_) {
      CellSites out;
      std::memcpy(&out, cells + sizeof(CellSites) * std::size_t(i), sizeof(CellSites));
      return out;
    }
    std::uint16_t codes[2];
    std::memcpy(codes, cells + 4 * i, 4);
    return {offset_of_[codes[0]], offset_of_[codes[1]]};
  }
  /// The tables' bytes.
  [[nodiscard]] std::size_t memory_bytes() const {
    return offset_of_.capacity() * sizeof(SiteOffset) + code_of_.capacity() * sizeof(std::uint16_t);
  }
  /// Where cell i of a coded brick starts (to prefetch it).
  [[nodiscard]] const unsigned char* cell_address(const unsigned char* cells, int i) const {
    return cells + bytes_per_cell() * std::size_t(i);
  }

 private:
  [[nodiscard]] std::size_t index(SiteOffset o) const {
    return (std::size_t(o.z + window_) * std::size_t(side_) + std::size_t(o.y + window_)) * std::size_t(side_) +
           std::size_t(o.x + window_);
  }
  [[nodiscard]] std::uint16_t code(SiteOffset o) const {
    if (o.none()) return kNoneCode;
    UMBRA_ASSERT(o.x >= -window_ && o.x <= window_ && o.y >= -window_ && o.y <= window_ && o.z >= -window_ &&
                 o.z <= window_);
    const std::uint16_t c = code_of_[index(o)];
    UMBRA_ASSERT(c != kNoneCode);  // every offset a field keeps is within the cap
    return c;
  }

  int window_;
  int side_;
  bool compact_ = false;
  std::vector<SiteOffset> offset_of_;      // by code
  std::vector<std::uint16_t> code_of_;     // by (x, y, z) + window
};

}  // namespace umbra::detail
