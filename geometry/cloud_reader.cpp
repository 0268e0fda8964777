#include "geometry/cloud_reader.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <limits>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <vector>

namespace drom::geometry {

namespace {

[[noreturn]] void fail_at_line(const std::string& origin, std::size_t line, const std::string& what) {
  throw InputError(origin + ": line " + std::to_string(line) + ": " + what);
}
[[noreturn]] void fail_at_byte(const std::string& origin, std::size_t byte, const std::string& what) {
  throw InputError(origin + ": byte " + std::to_string(byte) + ": " + what);
}

// A token for messages: at most 40 characters, non-printable bytes escaped.
std::string shown(std::string_view token) {
  std::string s;
  for (const char c : token.substr(0, 40)) {
    if (c >= 32 && c < 127) s += c;
    else {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\x%02x", static_cast<unsigned char>(c));
      s += buffer;
    }
  }
  if (token.size() > 40) s += "...";
  return "'" + s + "'";
}

// A decimal number (no hexadecimal: std::from_chars in general format, an optional leading '+').
std::optional<double> parse_number(std::string_view token) {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);
    if (!token.empty() && (token.front() == '-' || token.front() == '+')) return std::nullopt;
  }
  if (token.empty()) return std::nullopt;
  double value = 0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value, std::chars_format::general);
  if (error != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\r' || c == '\v' || c == '\f'; }

// The line's tokens (views into the text); empty tokens between two commas are kept, so "1,,2" is
// three columns, one of them empty (an error), as a spreadsheet means it.
void split_line(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  const auto skip_blanks = [&] {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r' || line[i] == '\v' || line[i] == '\f')) ++i;
  };
  skip_blanks();
  while (i < line.size()) {
    const std::size_t start = i;
    while (i < line.size() && !is_separator(line[i])) ++i;
    tokens.push_back(line.substr(start, i - start));
    skip_blanks();
    if (i < line.size() && (line[i] == ',' || line[i] == ';')) {
      ++i;
      skip_blanks();
      if (i >= line.size()) tokens.push_back(line.substr(line.size()));  // a trailing separator: an empty last column
    }
  }
}

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

void check_unit_normal(const std::string& origin, std::size_t where, bool binary, const Eigen::Vector3d& n, Eigen::Vector3d& out) {
  const double length = n.norm();
  if (!(length > 1e-12) || !std::isfinite(length)) {
    const std::string what = "the normal (" + std::to_string(n.x()) + ", " + std::to_string(n.y()) + ", " + std::to_string(n.z()) + ") has no direction";
    if (binary) fail_at_byte(origin, where, what);
    fail_at_line(origin, where, what);
  }
  out = n / length;
}

// A point with a coordinate or a normal component that is not a finite number (a scanner's "no
// return"): an error when asked, else dropped and counted, the first one's place kept for the report.
void drop_not_finite(PointCloud& cloud, const CloudReadOptions& options, const std::string& origin, std::size_t where, bool binary, const std::string& what) {
  if (options.not_finite_is_error) {
    if (binary) fail_at_byte(origin, where, what);
    fail_at_line(origin, where, what);
  }
  if (cloud.dropped.not_finite++ == 0) cloud.dropped.first_not_finite = origin + (binary ? ": byte " : ": line ") + std::to_string(where) + ": " + what;
}

// One point read: kept (its normal made a unit vector when the file has normals), or dropped and
// counted when a coordinate or a normal component is not finite. `name` says which ("vertex 7").
void add_point(PointCloud& cloud, const CloudReadOptions& options, const std::string& origin, std::size_t where, bool binary, const std::string& name,
               const Eigen::Vector3d& p, const Eigen::Vector3d* n) {
  if (!p.allFinite() || (n && !n->allFinite())) {
    drop_not_finite(cloud, options, origin, where, binary, name + (p.allFinite() ? " has a normal" : " has a coordinate") + " that is not a finite number");
    return;
  }
  cloud.points.push_back(p);
  if (n) {
    cloud.normals.emplace_back();
    check_unit_normal(origin, where, binary, *n, cloud.normals.back());
  }
}

void require_points(const PointCloud& cloud, const std::string& origin) {
  if (cloud.points.empty()) throw InputError(origin + ": the cloud has no point");
}

}  // namespace

PointCloud parse_xyz(std::string_view text, const std::string& origin, const CloudReadOptions& options) {
  PointCloud cloud;
  cloud.origin = origin;
  std::vector<std::string_view> tokens;
  int column_x = 0, column_y = 1, column_z = 2, column_nx = -1, column_ny = -1, column_nz = -1;
  std::size_t columns = 0;      // every data line's count, fixed by the first
  bool header_allowed = true;   // only the first content line may name the columns
  bool named = false, six_unnamed = false;
  std::size_t line_number = 0, position = 0;
  cloud.points.reserve(std::min<std::size_t>(text.size() / 16, 100'000'000));
  while (position < text.size()) {
    std::size_t end = text.find('\n', position);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(position, end - position);
    position = end + 1;
    ++line_number;
    split_line(line, tokens);
    if (tokens.empty()) continue;
    if (tokens.front().starts_with("#") || tokens.front().starts_with("//")) continue;
    if (line.find('\0') != std::string_view::npos) fail_at_line(origin, line_number, "a NUL byte: this is not a text file (a binary PLY must start with 'ply')");
    std::array<std::optional<double>, 64> values{};
    bool any_number = false;
    for (std::size_t k = 0; k < tokens.size() && k < values.size(); ++k) {
      values[k] = parse_number(tokens[k]);
      if (values[k]) any_number = true;
    }
    if (!any_number && header_allowed) {
      // The column names.
      header_allowed = false;
      named = true;
      column_x = column_y = column_z = -1;
      for (std::size_t k = 0; k < tokens.size(); ++k) {
        const std::string name = lower(tokens[k]);
        int* slot = name == "x" ? &column_x : name == "y" ? &column_y : name == "z" ? &column_z : name == "nx" ? &column_nx : name == "ny" ? &column_ny
                                                                                                           : name == "nz" ? &column_nz : nullptr;
        if (!slot) continue;
        if (*slot >= 0) fail_at_line(origin, line_number, "the column " + shown(tokens[k]) + " is named twice");
        if (k >= values.size()) fail_at_line(origin, line_number, "the column " + shown(tokens[k]) + " is beyond the 64 columns read");
        *slot = static_cast<int>(k);
      }
      if (column_x < 0 || column_y < 0 || column_z < 0)
        fail_at_line(origin, line_number, "a header line must name the columns x, y and z (found " + std::to_string(tokens.size()) + " names, not all three)");
      const int normal_columns = (column_nx >= 0) + (column_ny >= 0) + (column_nz >= 0);
      if (normal_columns != 0 && normal_columns != 3) fail_at_line(origin, line_number, "nx, ny and nz are named together or not at all");
      columns = tokens.size();
      continue;
    }
    if (columns == 0) {
      columns = tokens.size();
      if (columns < 3) fail_at_line(origin, line_number, "expected at least 3 columns (x y z), found " + std::to_string(columns));
      six_unnamed = !named && columns == 6;
      if (six_unnamed) column_nx = 3, column_ny = 4, column_nz = 5;
    }
    header_allowed = false;
    if (tokens.size() != columns)
      fail_at_line(origin, line_number, "expected " + std::to_string(columns) + " columns, as on the first line of data, found " + std::to_string(tokens.size()));
    int not_finite = -1;
    for (const int k : {column_x, column_y, column_z, column_nx, column_ny, column_nz}) {
      if (k < 0) continue;
      const auto& v = values[static_cast<std::size_t>(k)];
      if (!v) fail_at_line(origin, line_number, "column " + std::to_string(k + 1) + ": expected a number, found " + shown(tokens[static_cast<std::size_t>(k)]));
      if (!std::isfinite(*v) && not_finite < 0) not_finite = k;
    }
    if (not_finite >= 0) {
      drop_not_finite(cloud, options, origin, line_number, false,
                      "column " + std::to_string(not_finite + 1) + ": " + shown(tokens[static_cast<std::size_t>(not_finite)]) + " is not a finite number");
      continue;
    }
    cloud.points.emplace_back(*values[static_cast<std::size_t>(column_x)], *values[static_cast<std::size_t>(column_y)], *values[static_cast<std::size_t>(column_z)]);
    if (column_nx >= 0) {
      const Eigen::Vector3d n(*values[static_cast<std::size_t>(column_nx)], *values[static_cast<std::size_t>(column_ny)], *values[static_cast<std::size_t>(column_nz)]);
      if (six_unnamed && std::abs(n.norm() - 1) > 1e-2)
        fail_at_line(origin, line_number,
                     "six unnamed columns are read as x y z nx ny nz, but columns 4-6 are not a unit normal (length " + std::to_string(n.norm()) +
                         "); name the columns on a first line (e.g. 'x y z r g b')");
      cloud.normals.emplace_back();
      check_unit_normal(origin, line_number, false, n, cloud.normals.back());
    }
  }
  require_points(cloud, origin);
  return cloud;
}

namespace {

enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::optional<PlyType> ply_type(std::string_view name) {
  if (name == "char" || name == "int8") return PlyType::int8;
  if (name == "uchar" || name == "uint8") return PlyType::uint8;
  if (name == "short" || name == "int16") return PlyType::int16;
  if (name == "ushort" || name == "uint16") return PlyType::uint16;
  if (name == "int" || name == "int32") return PlyType::int32;
  if (name == "uint" || name == "uint32") return PlyType::uint32;
  if (name == "float" || name == "float32") return PlyType::float32;
  if (name == "double" || name == "float64") return PlyType::float64;
  return std::nullopt;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::int8:
    case PlyType::uint8: return 1;
    case PlyType::int16:
    case PlyType::uint16: return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 1;
}

bool is_integer(PlyType t) { return t != PlyType::float32 && t != PlyType::float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;
  bool list = false;
  PlyType count_type = PlyType::uint8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t header_line = 0;
  bool fixed_size() const {
    return std::none_of(properties.begin(), properties.end(), [](const PlyProperty& p) { return p.list; });
  }
  std::size_t stride() const {
    std::size_t s = 0;
    for (const auto& p : properties) s += type_size(p.type);
    return s;
  }
};

// A binary value at `data` in the file's byte order.
double read_binary(const char* data, PlyType t, bool big_endian) {
  std::array<unsigned char, 8> b{};
  const std::size_t n = type_size(t);
  std::memcpy(b.data(), data, n);
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(n));
  switch (t) {
    case PlyType::int8: return static_cast<double>(static_cast<std::int8_t>(b[0]));
    case PlyType::uint8: return static_cast<double>(b[0]);
    case PlyType::int16: {
      std::int16_t v;
      std::memcpy(&v, b.data(), 2);
      return v;
    }
    case PlyType::uint16: {
      std::uint16_t v;
      std::memcpy(&v, b.data(), 2);
      return v;
    }
    case PlyType::int32: {
      std::int32_t v;
      std::memcpy(&v, b.data(), 4);
      return v;
    }
    case PlyType::uint32: {
      std::uint32_t v;
      std::memcpy(&v, b.data(), 4);
      return v;
    }
    case PlyType::float32: {
      float v;
      std::memcpy(&v, b.data(), 4);
      return static_cast<double>(v);
    }
    case PlyType::float64: {
      double v;
      std::memcpy(&v, b.data(), 8);
      return v;
    }
  }
  return 0;
}

}  // namespace

PointCloud parse_ply(std::string_view bytes, const std::string& origin, const CloudReadOptions& options) {
  // The header: ASCII lines up to "end_header".
  if (!bytes.starts_with("ply\n") && !bytes.starts_with("ply\r\n")) throw InputError(origin + ": line 1: a PLY file starts with the line 'ply'");
  enum class Format { ascii, little, big } format = Format::ascii;
  bool have_format = false;
  std::vector<PlyElement> elements;
  std::size_t position = 0, line_number = 0;
  bool ended = false;
  std::vector<std::string_view> words;
  while (position < bytes.size()) {
    std::size_t end = bytes.find('\n', position);
    if (end == std::string_view::npos) break;
    std::string_view line = bytes.substr(position, end - position);
    position = end + 1;
    ++line_number;
    if (line.ends_with('\r')) line.remove_suffix(1);
    words.clear();
    for (std::size_t i = 0; i < line.size();) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
      const std::size_t start = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
      if (i > start) words.push_back(line.substr(start, i - start));
    }
    if (line_number == 1) continue;  // "ply"
    if (words.empty()) continue;
    const std::string_view key = words[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      ended = true;
      break;
    }
    if (key == "format") {
      if (words.size() != 3) fail_at_line(origin, line_number, "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (words[1] == "ascii") format = Format::ascii;
      else if (words[1] == "binary_little_endian") format = Format::little;
      else if (words[1] == "binary_big_endian") format = Format::big;
      else fail_at_line(origin, line_number, "unknown PLY format " + shown(words[1]) + " (ascii, binary_little_endian or binary_big_endian)");
      if (words[2] != "1.0") fail_at_line(origin, line_number, "PLY version " + shown(words[2]) + ": only 1.0 is defined");
      have_format = true;
    } else if (key == "element") {
      if (words.size() != 3) fail_at_line(origin, line_number, "expected 'element NAME COUNT'");
      std::uint64_t count = 0;
      const auto [p, e] = std::from_chars(words[2].data(), words[2].data() + words[2].size(), count);
      if (e != std::errc() || p != words[2].data() + words[2].size() || count > (std::uint64_t{1} << 40))
        fail_at_line(origin, line_number, "element count " + shown(words[2]) + " is not a count (a non-negative integer below 2^40)");
      elements.push_back({std::string(words[1]), count, {}, line_number});
    } else if (key == "property") {
      if (elements.empty()) fail_at_line(origin, line_number, "a property before any element");
      PlyProperty p;
      if (words.size() == 5 && words[1] == "list") {
        const auto count_type = ply_type(words[2]), item_type = ply_type(words[3]);
        if (!count_type || !is_integer(*count_type)) fail_at_line(origin, line_number, "a list's count type must be an integer type, found " + shown(words[2]));
        if (!item_type) fail_at_line(origin, line_number, "unknown property type " + shown(words[3]));
        p = {std::string(words[4]), *item_type, true, *count_type};
      } else if (words.size() == 3) {
        const auto type = ply_type(words[1]);
        if (!type) fail_at_line(origin, line_number, "unknown property type " + shown(words[1]) + " (char uchar short ushort int uint float double, or int8 ... float64)");
        p = {std::string(words[2]), *type, false, PlyType::uint8};
      } else {
        fail_at_line(origin, line_number, "expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME'");
      }
      for (const auto& q : elements.back().properties)
        if (q.name == p.name) fail_at_line(origin, line_number, "property " + shown(p.name) + " given twice");
      elements.back().properties.push_back(p);
    } else {
      fail_at_line(origin, line_number, "unknown header line starting with " + shown(key));
    }
  }
  if (!ended) throw InputError(origin + ": the PLY header has no 'end_header' line");
  if (!have_format) throw InputError(origin + ": the PLY header has no 'format' line");
  const auto vertex = std::find_if(elements.begin(), elements.end(), [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == elements.end()) throw InputError(origin + ": the PLY header declares no 'vertex' element");
  const auto find_property = [&](const char* name) -> int {
    for (std::size_t k = 0; k < vertex->properties.size(); ++k)
      if (vertex->properties[k].name == name) return static_cast<int>(k);
    return -1;
  };
  const int px = find_property("x"), py = find_property("y"), pz = find_property("z");
  const int pnx = find_property("nx"), pny = find_property("ny"), pnz = find_property("nz");
  for (const auto& [k, name] : {std::pair{px, "x"}, std::pair{py, "y"}, std::pair{pz, "z"}})
    if (k < 0) fail_at_line(origin, vertex->header_line, "the vertex element has no property '" + std::string(name) + "' (x, y and z are required)");
  const int normal_count = (pnx >= 0) + (pny >= 0) + (pnz >= 0);
  if (normal_count != 0 && normal_count != 3) fail_at_line(origin, vertex->header_line, "the vertex element has some of nx, ny, nz but not all three");
  for (const int k : {px, py, pz, pnx, pny, pnz})
    if (k >= 0 && vertex->properties[static_cast<std::size_t>(k)].list)
      fail_at_line(origin, vertex->header_line, "vertex property " + shown(vertex->properties[static_cast<std::size_t>(k)].name) + " is a list, not a number");
  const bool with_normals = normal_count == 3;

  PointCloud cloud;
  cloud.origin = origin;
  const std::size_t data_start = position;
  // A count is believed only as far as the bytes can hold it (a fuzzed header must not allocate terabytes).
  const std::size_t remaining = bytes.size() - data_start;
  if (format == Format::ascii) {
    if (vertex->count > remaining / 2 + 1)
      throw InputError(origin + ": line " + std::to_string(vertex->header_line) + ": " + std::to_string(vertex->count) + " vertices declared, but only " +
                       std::to_string(remaining) + " bytes of data follow the header");
  } else {
    const std::size_t smallest = std::max<std::size_t>(1, vertex->fixed_size() ? vertex->stride() : vertex->properties.size());
    if (vertex->count > remaining / smallest)
      fail_at_byte(origin, data_start,
                   std::to_string(vertex->count) + " vertices of at least " + std::to_string(smallest) + " bytes declared, but only " + std::to_string(remaining) +
                       " bytes follow the header");
  }
  cloud.points.reserve(static_cast<std::size_t>(vertex->count));
  if (with_normals) cloud.normals.reserve(static_cast<std::size_t>(vertex->count));

  if (format == Format::ascii) {
    std::vector<std::string_view> tokens;
    std::vector<double> values;
    for (const auto& element : elements) {
      const bool is_vertex = &element == &*vertex;
      for (std::uint64_t i = 0; i < element.count; ++i) {
        // One element instance per line; blank lines skipped.
        std::string_view line;
        do {
          if (position >= bytes.size())
            throw InputError(origin + ": line " + std::to_string(line_number + 1) + ": the data ends after " + std::to_string(i) + " of the " +
                             std::to_string(element.count) + " '" + element.name + "' elements declared");
          std::size_t end = bytes.find('\n', position);
          if (end == std::string_view::npos) end = bytes.size();
          line = bytes.substr(position, end - position);
          position = end + 1;
          ++line_number;
          split_line(line, tokens);
        } while (tokens.empty());
        values.clear();
        std::size_t t = 0;
        for (const auto& p : element.properties) {
          const auto take = [&](PlyType type) {
            if (t >= tokens.size()) fail_at_line(origin, line_number, "'" + element.name + "' " + std::to_string(i) + ": too few values (property " + shown(p.name) + " missing)");
            const auto v = parse_number(tokens[t]);
            if (!v) fail_at_line(origin, line_number, "property " + shown(p.name) + ": expected a number, found " + shown(tokens[t]));
            if (is_integer(type) && *v != std::floor(*v)) fail_at_line(origin, line_number, "property " + shown(p.name) + ": expected an integer, found " + shown(tokens[t]));
            ++t;
            return *v;
          };
          if (p.list) {
            const double count = take(p.count_type);
            if (count < 0 || count > static_cast<double>(tokens.size())) fail_at_line(origin, line_number, "list " + shown(p.name) + ": a count of " + std::to_string(count) + " items does not fit the line");
            for (int k = 0; k < static_cast<int>(count); ++k) take(p.type);
            values.push_back(0);
          } else {
            values.push_back(take(p.type));
          }
        }
        if (t != tokens.size())
          fail_at_line(origin, line_number, "'" + element.name + "' " + std::to_string(i) + ": " + std::to_string(tokens.size() - t) + " values more than its properties declare");
        if (!is_vertex) continue;
        const Eigen::Vector3d p(values[static_cast<std::size_t>(px)], values[static_cast<std::size_t>(py)], values[static_cast<std::size_t>(pz)]);
        const Eigen::Vector3d n = with_normals ? Eigen::Vector3d(values[static_cast<std::size_t>(pnx)], values[static_cast<std::size_t>(pny)], values[static_cast<std::size_t>(pnz)])
                                               : Eigen::Vector3d::Zero();
        add_point(cloud, options, origin, line_number, false, "vertex " + std::to_string(i), p, with_normals ? &n : nullptr);
      }
    }
    // Every element read: what follows is data the header does not declare (its vertex count is short).
    while (position < bytes.size()) {
      std::size_t end = bytes.find('\n', position);
      if (end == std::string_view::npos) end = bytes.size();
      const std::string_view line = bytes.substr(position, end - position);
      position = end + 1;
      ++line_number;
      split_line(line, tokens);
      if (!tokens.empty())
        fail_at_line(origin, line_number,
                     "data after the " + std::to_string(vertex->count) + " vertices" + (elements.size() > 1 ? " and the other elements" : std::string()) +
                         " the header declares (line " + std::to_string(vertex->header_line) + "): the header's count is wrong, or two files were joined");
    }
  } else {
    const bool big = format == Format::big;
    for (const auto& element : elements) {
      const bool is_vertex = &element == &*vertex;
      if (!is_vertex && element.fixed_size()) {
        const std::size_t stride = element.stride();
        if (element.count > (bytes.size() - position) / std::max<std::size_t>(stride, 1))
          fail_at_byte(origin, position, "the '" + element.name + "' element's " + std::to_string(element.count) + " records of " + std::to_string(stride) + " bytes run past the end of the file");
        position += static_cast<std::size_t>(element.count) * stride;
        continue;
      }
      std::vector<std::size_t> offsets(element.properties.size());
      for (std::uint64_t i = 0; i < element.count; ++i) {
        const std::size_t record = position;
        for (std::size_t k = 0; k < element.properties.size(); ++k) {
          const auto& p = element.properties[k];
          offsets[k] = position;
          if (p.list) {
            if (bytes.size() - position < type_size(p.count_type))
              fail_at_byte(origin, position, "the data ends inside '" + element.name + "' " + std::to_string(i) + " (list " + shown(p.name) + "'s count)");
            const double count = read_binary(bytes.data() + position, p.count_type, big);
            position += type_size(p.count_type);
            if (count < 0 || count * static_cast<double>(type_size(p.type)) > static_cast<double>(bytes.size() - position))
              fail_at_byte(origin, position, "list " + shown(p.name) + " of '" + element.name + "' " + std::to_string(i) + " claims " + std::to_string(count) + " items past the end of the file");
            position += static_cast<std::size_t>(count) * type_size(p.type);
          } else {
            if (bytes.size() - position < type_size(p.type))
              fail_at_byte(origin, position, "the data ends inside '" + element.name + "' " + std::to_string(i) + " of " + std::to_string(element.count) + " (property " + shown(p.name) + ")");
            position += type_size(p.type);
          }
        }
        if (!is_vertex) continue;
        const auto value = [&](int k) { return read_binary(bytes.data() + offsets[static_cast<std::size_t>(k)], element.properties[static_cast<std::size_t>(k)].type, big); };
        const Eigen::Vector3d p(value(px), value(py), value(pz));
        const Eigen::Vector3d n = with_normals ? Eigen::Vector3d(value(pnx), value(pny), value(pnz)) : Eigen::Vector3d::Zero();
        add_point(cloud, options, origin, record, true, "vertex " + std::to_string(i), p, with_normals ? &n : nullptr);
      }
    }
    // A newline after the data is common; anything more is data the header does not declare.
    std::size_t trailing = position;
    while (trailing < bytes.size() && (bytes[trailing] == '\n' || bytes[trailing] == '\r')) ++trailing;
    if (trailing < bytes.size())
      fail_at_byte(origin, position,
                   std::to_string(bytes.size() - position) + " bytes after the " + std::to_string(vertex->count) + " vertices" +
                       (elements.size() > 1 ? " and the other elements" : std::string()) + " the header declares (line " + std::to_string(vertex->header_line) +
                       "): the header's count is wrong, or two files were joined");
  }
  require_points(cloud, origin);
  return cloud;
}

// ---- PCD (the Point Cloud Library's format, v0.5 to v0.7) -----------------------------------

namespace {

struct PcdField {
  std::string name;
  std::size_t size = 0;   // bytes per value: 1, 2, 4 or 8
  char type = 'F';        // I (signed), U (unsigned), F (float)
  std::size_t count = 1;  // values per point
  std::size_t offset = 0; // bytes from the start of a point (binary), or values before it (ascii)
};

double pcd_value(const char* data, const PcdField& f) {
  auto get = [&](auto v) {
    std::memcpy(&v, data, sizeof v);  // PCD is little-endian, as every machine drom builds on
    return static_cast<double>(v);
  };
  if (f.type == 'F') return f.size == 4 ? get(float{}) : get(double{});
  if (f.type == 'I') return f.size == 1 ? get(std::int8_t{}) : f.size == 2 ? get(std::int16_t{}) : f.size == 4 ? get(std::int32_t{}) : get(std::int64_t{});
  return f.size == 1 ? get(std::uint8_t{}) : f.size == 2 ? get(std::uint16_t{}) : f.size == 4 ? get(std::uint32_t{}) : get(std::uint64_t{});
}

// LZF (liblzf's format, as PCL's binary_compressed writes it): a control byte below 32 starts a run
// of that many + 1 literal bytes; above, a back-reference of (ctrl >> 5) + 2 bytes (7: plus the next
// byte) that many + 1 bytes back (the low 5 bits, then the next byte). Every read and write bounded.
std::string lzf_decompress(std::string_view in, std::size_t expected, const std::string& origin, std::size_t at) {
  std::string out;
  out.reserve(expected);
  std::size_t i = 0;
  while (i < in.size()) {
    const auto ctrl = static_cast<unsigned char>(in[i++]);
    if (ctrl < 32) {
      const std::size_t run = ctrl + 1u;
      if (run > in.size() - i) fail_at_byte(origin, at + i, "the compressed data ends inside a literal run");
      if (run > expected - out.size()) fail_at_byte(origin, at + i, "the compressed data holds more than the uncompressed size its header gives");
      out.append(in.substr(i, run));
      i += run;
      continue;
    }
    std::size_t length = ctrl >> 5;
    if (length == 7) {
      if (i >= in.size()) fail_at_byte(origin, at + i, "the compressed data ends inside a back-reference");
      length += static_cast<unsigned char>(in[i++]);
    }
    if (i >= in.size()) fail_at_byte(origin, at + i, "the compressed data ends inside a back-reference");
    const std::size_t back = ((ctrl & 0x1fu) << 8) + static_cast<unsigned char>(in[i++]) + 1;
    length += 2;
    if (back > out.size()) fail_at_byte(origin, at + i, "a back-reference before the start of the data");
    if (length > expected - out.size()) fail_at_byte(origin, at + i, "the compressed data holds more than the uncompressed size its header gives");
    for (std::size_t k = 0; k < length; ++k) out.push_back(out[out.size() - back]);  // may overlap what it writes
  }
  if (out.size() != expected)
    fail_at_byte(origin, at + i, "the compressed data gives " + std::to_string(out.size()) + " bytes, the header " + std::to_string(expected));
  return out;
}

}  // namespace

PointCloud parse_pcd(std::string_view bytes, const std::string& origin, const CloudReadOptions& options) {
  PointCloud cloud;
  cloud.origin = origin;
  std::vector<PcdField> fields;
  std::vector<std::string_view> sizes, types, counts;
  std::uint64_t width = 0, height = 1, points = 0;
  bool has_width = false, has_points = false;
  std::string data;
  std::size_t position = 0, line_no = 0, fields_line = 0, count_line = 0;
  auto count_of = [&](std::string_view token, const std::string& key) {
    const auto v = parse_number(token);
    if (!v || *v < 0 || *v != std::floor(*v) || *v > 1e12) fail_at_line(origin, line_no, key + ": expected a whole number, got '" + shown(token) + "'");
    return static_cast<std::uint64_t>(*v);
  };
  std::vector<std::string_view> tokens;
  while (data.empty()) {
    if (position >= bytes.size()) fail_at_line(origin, line_no, "the header ends before its DATA line");
    const std::size_t end = std::min(bytes.find('\n', position), bytes.size());
    const std::string_view raw = bytes.substr(position, end - position);
    position = end + 1;
    ++line_no;
    const std::string_view line = raw.substr(0, raw.find('#'));
    split_line(line, tokens);
    if (tokens.empty()) continue;
    const std::string key = lower(tokens.front());
    const std::vector<std::string_view> values(tokens.begin() + 1, tokens.end());
    if (key == "version" || key == "viewpoint") continue;
    if (key == "fields") {
      fields_line = line_no;
      for (auto v : values) fields.push_back({lower(v)});
    } else if (key == "size") {
      sizes = values;
    } else if (key == "type") {
      types = values;
    } else if (key == "count") {
      counts = values;
    } else if (key == "width") {
      width = values.size() == 1 ? count_of(values[0], "WIDTH") : 0, has_width = values.size() == 1;
      if (!has_points) count_line = line_no;
    } else if (key == "height") {
      height = values.size() == 1 ? count_of(values[0], "HEIGHT") : 0;
    } else if (key == "points") {
      points = values.size() == 1 ? count_of(values[0], "POINTS") : 0, has_points = values.size() == 1;
      count_line = line_no;
    } else if (key == "data") {
      data = values.size() == 1 ? lower(values[0]) : "?";
      if (data != "ascii" && data != "binary" && data != "binary_compressed")
        fail_at_line(origin, line_no, "DATA: expected ascii, binary or binary_compressed, got " + shown(line));
    } else {
      fail_at_line(origin, line_no, "expected a PCD header line (VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA), got " + shown(raw));
    }
  }
  const std::size_t data_line = line_no;
  if (fields.empty()) fail_at_line(origin, data_line, "the header has no FIELDS line");
  if (sizes.size() != fields.size() || types.size() != fields.size() || (!counts.empty() && counts.size() != fields.size()))
    fail_at_line(origin, fields_line, "FIELDS names " + std::to_string(fields.size()) + " fields, SIZE " + std::to_string(sizes.size()) + ", TYPE " +
                                          std::to_string(types.size()) + (counts.empty() ? std::string() : ", COUNT " + std::to_string(counts.size())) + ": one each expected");
  if (static_cast<double>(width) * static_cast<double>(height) > 1e12) fail_at_line(origin, data_line, "WIDTH x HEIGHT is over 10^12 points");
  if (!has_points) {
    if (!has_width) fail_at_line(origin, data_line, "the header gives neither POINTS nor WIDTH");
    points = width * height;
  }
  if (has_width && width * height != points)
    fail_at_line(origin, data_line, "POINTS " + std::to_string(points) + " is not WIDTH x HEIGHT = " + std::to_string(width * height));
  std::size_t stride = 0, values_per_point = 0;
  int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    PcdField& f = fields[k];
    const auto size = parse_number(sizes[k]);
    const std::string type = lower(types[k]);
    if (!size || (*size != 1 && *size != 2 && *size != 4 && *size != 8)) fail_at_line(origin, fields_line, "field " + f.name + ": SIZE must be 1, 2, 4 or 8");
    if (type != "i" && type != "u" && type != "f") fail_at_line(origin, fields_line, "field " + f.name + ": TYPE must be I, U or F");
    f.size = static_cast<std::size_t>(*size), f.type = static_cast<char>(std::toupper(type[0]));
    if (f.type == 'F' && f.size != 4 && f.size != 8) fail_at_line(origin, fields_line, "field " + f.name + ": a float (F) has SIZE 4 or 8");
    f.count = counts.empty() ? 1 : static_cast<std::size_t>(count_of(counts[k], "COUNT"));
    if (f.count == 0 || f.count > 100000) fail_at_line(origin, fields_line, "field " + f.name + ": COUNT must be 1 to 100000");
    f.offset = data == "ascii" ? values_per_point : stride;
    stride += f.size * f.count, values_per_point += f.count;
    if (values_per_point > 1000000) fail_at_line(origin, fields_line, "the fields hold over 10^6 values per point");
    int* slot = f.name == "x" ? &ix : f.name == "y" ? &iy : f.name == "z" ? &iz : f.name == "normal_x" ? &inx : f.name == "normal_y" ? &iny : f.name == "normal_z" ? &inz : nullptr;
    if (!slot) continue;
    if (*slot >= 0) fail_at_line(origin, fields_line, "field " + f.name + " is named twice");
    if (f.count != 1) fail_at_line(origin, fields_line, "field " + f.name + ": COUNT must be 1");
    *slot = static_cast<int>(k);
  }
  if (ix < 0 || iy < 0 || iz < 0) fail_at_line(origin, fields_line, "FIELDS must name x, y and z");
  const int normal_fields = (inx >= 0) + (iny >= 0) + (inz >= 0);
  if (normal_fields != 0 && normal_fields != 3) fail_at_line(origin, fields_line, "FIELDS names some of normal_x, normal_y, normal_z: all three or none");
  const bool with_normals = normal_fields == 3;
  auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n, std::size_t where, bool binary, std::uint64_t i) {
    add_point(cloud, options, origin, where, binary, "point " + std::to_string(i), p, with_normals ? &n : nullptr);
  };
  if (data == "ascii") {
    std::uint64_t read = 0;
    std::vector<double> v(values_per_point);
    while (position < bytes.size()) {
      const std::size_t end = std::min(bytes.find('\n', position), bytes.size());
      const std::string_view line = bytes.substr(position, end - position);
      position = end + 1;
      ++line_no;
      split_line(line, tokens);
      if (tokens.empty()) continue;
      if (read == points)
        fail_at_line(origin, line_no, "a point beyond the " + std::to_string(points) + " the header declares (line " + std::to_string(count_line) +
                                          "): the count is wrong, or two files were joined");
      if (tokens.size() != values_per_point)
        fail_at_line(origin, line_no, "expected " + std::to_string(values_per_point) + " values (the header's fields and counts), got " + std::to_string(tokens.size()));
      for (std::size_t k = 0; k < values_per_point; ++k) {
        const auto value = parse_number(tokens[k]);
        if (!value) fail_at_line(origin, line_no, shown(tokens[k]) + " is not a number");
        v[k] = *value;
      }
      auto at = [&](int k) { return v[fields[static_cast<std::size_t>(k)].offset]; };
      add({at(ix), at(iy), at(iz)}, with_normals ? Eigen::Vector3d(at(inx), at(iny), at(inz)) : Eigen::Vector3d::Zero(), line_no, false, read);
      ++read;
    }
    if (read != points)
      fail_at_line(origin, line_no, "the file holds " + std::to_string(read) + " points, the header (line " + std::to_string(count_line) + ") " + std::to_string(points));
    require_points(cloud, origin);
    return cloud;
  }
  // Binary: the points one after another, each its fields in order. Compressed: LZF over the fields
  // one after another (every point's x, then every y, ...), as PCL writes it.
  if (stride == 0 || points > (std::numeric_limits<std::size_t>::max() / stride)) fail_at_line(origin, data_line, "the points' size overflows");
  const std::size_t total = static_cast<std::size_t>(points) * stride;
  std::string_view body;
  std::string decompressed;
  const std::size_t body_at = position;
  if (data == "binary") {
    if (bytes.size() < position || bytes.size() - position < total)
      fail_at_byte(origin, std::min(bytes.size(), position), "the data ends before the " + std::to_string(points) + " points of " + std::to_string(stride) + " bytes the header declares");
    if (bytes.size() - position > total)
      fail_at_byte(origin, position + total, std::to_string(bytes.size() - position - total) + " bytes after the " + std::to_string(points) +
                                                 " points the header declares: the header's count is wrong, or two files were joined");
    body = bytes.substr(position, total);
  } else {
    if (bytes.size() < position || bytes.size() - position < 8) fail_at_byte(origin, std::min(bytes.size(), position), "the compressed data has no sizes");
    std::uint32_t compressed = 0, uncompressed = 0;
    std::memcpy(&compressed, bytes.data() + position, 4);
    std::memcpy(&uncompressed, bytes.data() + position + 4, 4);
    if (uncompressed != total)
      fail_at_byte(origin, position + 4, "the uncompressed size " + std::to_string(uncompressed) + " is not the " + std::to_string(points) + " points of " + std::to_string(stride) + " bytes the header declares");
    if (bytes.size() - position - 8 < compressed) fail_at_byte(origin, position, "the compressed data (" + std::to_string(compressed) + " bytes) runs past the end of the file");
    if (bytes.size() - position - 8 > compressed)
      fail_at_byte(origin, position + 8 + compressed, std::to_string(bytes.size() - position - 8 - compressed) + " bytes after the compressed data");
    // LZF gives at most 264 bytes for a 2-byte back-reference: a larger claim is a lie, and it is
    // found before the memory is taken for it.
    if (static_cast<double>(uncompressed) > 132.0 * static_cast<double>(compressed) + 32)
      fail_at_byte(origin, position + 4, "the uncompressed size " + std::to_string(uncompressed) + " cannot come from " + std::to_string(compressed) + " compressed bytes");
    decompressed = total == 0 ? std::string() : lzf_decompress(bytes.substr(position + 8, compressed), total, origin, position + 8);
    body = decompressed;
  }
  const bool by_field = data == "binary_compressed";
  auto value_of = [&](int k, std::uint64_t i) {
    const PcdField& f = fields[static_cast<std::size_t>(k)];
    const std::size_t at = by_field ? static_cast<std::size_t>(points) * f.offset + static_cast<std::size_t>(i) * f.size : static_cast<std::size_t>(i) * stride + f.offset;
    return pcd_value(body.data() + at, f);
  };
  for (std::uint64_t i = 0; i < points; ++i) {
    const std::size_t where = by_field ? body_at : body_at + static_cast<std::size_t>(i) * stride;
    add({value_of(ix, i), value_of(iy, i), value_of(iz, i)}, with_normals ? Eigen::Vector3d(value_of(inx, i), value_of(iny, i), value_of(inz, i)) : Eigen::Vector3d::Zero(), where,
        true, i);
  }
  require_points(cloud, origin);
  return cloud;
}

namespace {

// A PCD header: its first line that is not a comment ('#') starts with VERSION or FIELDS.
bool looks_like_pcd(std::string_view bytes) {
  std::size_t position = 0;
  while (position < bytes.size()) {
    const std::size_t end = std::min(bytes.find('\n', position), bytes.size());
    std::string_view line = bytes.substr(position, end - position);
    position = end + 1;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string_view::npos || line[first] == '#') continue;
    line = line.substr(first);
    return line.starts_with("VERSION") || line.starts_with("FIELDS");
  }
  return false;
}

}  // namespace

PointCloud parse_cloud(std::string_view bytes, const std::string& origin, const CloudReadOptions& options) {
  if (bytes.starts_with("ply\n") || bytes.starts_with("ply\r\n")) return parse_ply(bytes, origin, options);
  if (looks_like_pcd(bytes)) return parse_pcd(bytes, origin, options);
  return parse_xyz(bytes, origin, options);
}

PointCloud read_cloud(const std::filesystem::path& path, double scale, const CloudReadOptions& options) {
  if (!(scale > 0) || !std::isfinite(scale)) throw InputError(path.string() + ": the scale factor must be a positive number, not " + std::to_string(scale));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the cloud file (missing or unreadable)");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path.string() + ": reading the cloud file failed");
  if (bytes.empty()) throw InputError(path.string() + ": the cloud file is empty");
  PointCloud cloud = parse_cloud(bytes, path.string(), options);
  if (scale != 1)
    for (auto& p : cloud.points) p *= scale;
  return cloud;
}

}  // namespace drom::geometry
