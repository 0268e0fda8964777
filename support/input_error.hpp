#pragma once
// The one exception type for bad user input (case files, meshes, G-code, measurements).
// The CLI turns it into a message on stderr and exit code 2; anything else is a bug.
#include <stdexcept>
#include <string>
#include <string_view>

namespace drom {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Text taken from an input, fit to quote in a message: a byte that is not printable ASCII as \xNN
// (a NUL would cut the message short), and no more than `max` characters.
inline std::string printable(std::string_view text, std::size_t max = 80) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (const char c : text) {
    if (out.size() >= max) return out + "...";
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) {
      out += c;
    } else {
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    }
  }
  return out;
}

}  // namespace drom
