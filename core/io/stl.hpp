#pragma once
// STL triangle meshes for mesh walls: ASCII ("solid ... facet normal ... vertex ...") and binary
// (80-byte header, uint32 count, 50 bytes per facet). Facet normals are ignored on reading (the
// contact is two-sided) and written from the vertex order. Coincident vertices are merged.
#include <string>

#include "core/walls/mesh.hpp"

namespace demcal::io {

/// Reads an ASCII or binary STL (detected from the content); `scale` multiplies coordinates
/// (e.g. 1e-3 for a file in mm). InputError naming the file on a malformed file.
walls::Mesh read_stl(const std::string& path, double scale = 1.0);
/// The same from the file's bytes; `path` names the source in errors.
walls::Mesh parse_stl(const std::string& data, const std::string& path, double scale = 1.0);
void write_stl_ascii(const std::string& path, const walls::Mesh& mesh,
                     const std::string& name = "demcal");
void write_stl_binary(const std::string& path, const walls::Mesh& mesh);

}  // namespace demcal::io
