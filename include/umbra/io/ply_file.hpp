// PLY point clouds (.ply): reading the vertices of a PLY file as one scan.
//
// PLY (the Stanford polygon format) is what most scanning and meshing tools
// export: a text header declaring elements (vertex, face, ...) with typed
// properties, then the data as text ("format ascii 1.0", one element
// instance per line) or binary ("binary_little_endian 1.0" /
// "binary_big_endian 1.0"). umbra reads the x, y, z properties of the
// "vertex" element (any PLY scalar type, rounded to float) and, when all
// three are present, the colors red/green/blue (or diffuse_red/...): uchar
// as is, ushort scaled from 0..65535, float/double scaled from 0..1, other
// integers clamped to 0..255. Every other property and element (normals,
// alpha, faces with list properties, ...) is skipped but still checked, so a
// truncated file is always reported. The file carries no sensor pose: the
// points are used as they are and the sensor origin is the caller's. The
// header is validated when the file is opened (counts against the file
// size, so a hostile count never causes a large allocation); the data is
// read in next() through a fixed-size buffer. Errors are FormatError with
// the line (header, ascii data) or byte offset (binary data).
#pragma once

#include <filesystem>
#include <memory>

#include "umbra/core/vec3.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {

/// Opens a PLY file as a source of exactly one scan with sensor origin
/// `origin`. Throws std::runtime_error("cannot open FILE: reason") when the
/// file cannot be opened, FormatError for a bad header (here) or bad data
/// (from next()). open_scan_source() calls this for the "ply" format.
std::unique_ptr<ScanSource> open_ply_file(const std::filesystem::path& path, Vec3f origin = {});

}  // namespace umbra
