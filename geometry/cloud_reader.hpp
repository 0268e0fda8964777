#pragma once
// Point clouds read from the files scanners and their software write: XYZ text (any of space, tab,
// comma or semicolon between columns, so CSV too), PLY (ascii, binary little- and big-endian) and PCD.
// Every entry point takes the bytes and the name of where they came from, so a fuzzer can call it
// directly. Malformed input throws InputError naming the origin, the line (text) or the byte offset
// (binary) and what was expected; it never crashes and never yields a silently wrong cloud: missing
// x/y/z, truncated data, data beyond what a PLY header declares and empty clouds are all errors.
// A point with a NaN or infinite coordinate or normal component (a scanner's "no return") is dropped
// and counted in PointCloud::dropped, or is an error with CloudReadOptions::not_finite_is_error.
//
// XYZ/CSV: one point per line, '#' or '//' comment lines and blank lines skipped. An optional first
// line names the columns (x, y, z required; nx, ny, nz together or not at all; others ignored).
// Without it, the first three columns are x, y, z; a line of exactly six columns carries the normal in
// columns four to six (which must then be unit vectors; name the columns otherwise). Every line has
// the same number of columns.
// PLY: the "vertex" element's x, y, z (any numeric type) and nx, ny, nz when present; other elements
// (faces, ...) and properties are skipped, list properties included.
// PCD (the Point Cloud Library's format, v0.5-0.7; written by PCL, CloudCompare, many scanners'
// software): DATA ascii, binary or binary_compressed (LZF over the fields one after another), fields x,
// y, z and normal_x, normal_y, normal_z when present, any SIZE/TYPE/COUNT; the others (rgb,
// intensity, curvature, ...) skipped. POINTS must be WIDTH x HEIGHT and match the data, either way.
// An organised cloud's NaN points (no return) are dropped and counted like any other. Read by drom
// itself: the format is a header and a table, and PCL's reader would bring PCL's 300 MB of packages.
#include "geometry/point_cloud.hpp"

#include <filesystem>
#include <string>
#include <string_view>

namespace drom::geometry {

struct CloudReadOptions {
  bool not_finite_is_error = false;
};

PointCloud parse_xyz(std::string_view text, const std::string& origin, const CloudReadOptions& options = {});
PointCloud parse_ply(std::string_view bytes, const std::string& origin, const CloudReadOptions& options = {});
PointCloud parse_pcd(std::string_view bytes, const std::string& origin, const CloudReadOptions& options = {});
// PLY when the bytes start with "ply", PCD when the first line that is not a comment starts with
// VERSION or FIELDS, XYZ text otherwise.
PointCloud parse_cloud(std::string_view bytes, const std::string& origin, const CloudReadOptions& options = {});

// A file by its content (see parse_cloud); every coordinate multiplied by `scale` (the seed scaled its
// clouds by 7/20 and 1/3). Throws InputError when the file is missing or unreadable.
PointCloud read_cloud(const std::filesystem::path& path, double scale = 1, const CloudReadOptions& options = {});

}  // namespace drom::geometry
