// Spill files: what leaves a moving window's box (umbra/map/moving_window.hpp),
// kept on disk piece by piece so that it can be put back together later.
//
// Format (docs/map-format.md, "Spill files"): a sequence of pieces and
// nothing else; an empty file holds none. A piece is
//
//   bytes 0-7    magic "UMBSPILL"
//   bytes 8-15   N, little-endian unsigned 64-bit: the size of what follows
//   16 .. 16+N   a complete .umb map file (map_file.hpp) holding the voxels
//                that left the box in one move, the rest unknown
//
// append_spill_piece adds one piece with one write at the end of the file
// and syncs it to disk (fdatasync; for a new file its folder too) before it
// returns; if the write or the sync fails (disk full, ...) the file is cut
// back to its old size, so the file never holds part of a piece because of
// an error (if the cut fails too, the piece's magic is zeroed, so that
// readers stop there with an error instead of counting it twice). Pieces are only appended, so a crash or a process killed in the
// middle of an append can leave part of the last piece at most, never
// damage an earlier one: load_spill then names the byte where the whole
// pieces end, and a file cut there holds them all.
//
// load_spill reads every piece and adds them up with OccupancyMap::merge,
// so a voxel that left the box, came back and left again gets the sum of
// both stays: merged with the window's map at the end, the result is the
// map of the whole run without a window, voxel for voxel, wherever no
// voxel reached the clamping bounds (the exact statement in docs/design.md,
// "A map that moves"). `umbra merge` takes spill files (.umbs) as inputs.
//
// Errors: malformed files throw FormatError "FILE: byte OFFSET: what was
// expected, what was found"; an error inside a piece's map file names the
// piece and where it starts, with offsets counted from the start of that map
// file. I/O failures throw std::runtime_error naming the path and the
// system's reason.
#pragma once

#include <filesystem>
#include <functional>

#include "umbra/core/function_ref.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

/// Appends `piece` to the spill file `path` (created when missing).
void append_spill_piece(const std::filesystem::path& path, const OccupancyMap& piece);

/// A MovingWindow::spill that appends every piece to `path` (append_spill_piece).
[[nodiscard]] std::function<void(const OccupancyMap&)> spill_to_file(const std::filesystem::path& path);

/// Calls visit(piece) for every piece in file order; returns how many there were.
std::size_t for_each_spill_piece(const std::filesystem::path& path, FunctionRef<void(OccupancyMap&& piece)> visit);

/// Every piece of the file merged into one map (the first piece's settings;
/// the others must have its resolution and depth levels). Throws FormatError
/// also for a file that holds no piece.
[[nodiscard]] OccupancyMap load_spill(const std::filesystem::path& path);

}  // namespace umbra
