// ASCII point files ("x y z" or "x y z r g b" per line), plain or bz2-compressed.
//
// These are the simplest point-cloud files around (OctoMap's scan.dat, most
// tools' .xyz exports). A file holds one scan; it carries no sensor pose, so
// the caller supplies the origin. Files whose name ends in ".bz2" are
// decompressed on the fly while reading.
#pragma once

#include <filesystem>
#include <memory>

#include "umbra/core/vec3.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {

/// Opens an ASCII point file (decompressing it when the name ends in .bz2,
/// case-insensitive) as a source of exactly one scan whose sensor origin is
/// `origin`. Lines are "x y z" or "x y z r g b" (colors 0..255, all lines
/// alike); blank lines and lines starting with '#' are skipped; NaN and inf
/// coordinates are passed through. Throws std::runtime_error("cannot open
/// FILE: reason") when the file cannot be opened; malformed lines and corrupt
/// compressed data throw FormatError from ScanSource::next().
std::unique_ptr<ScanSource> open_xyz_file(const std::filesystem::path& path, Vec3f origin = {});

}  // namespace umbra
