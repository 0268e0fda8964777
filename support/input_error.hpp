#pragma once
// The one exception type for bad user input (case files, meshes, G-code, measurements).
// The CLI turns it into a message on stderr and exit code 2; anything else is a bug.
#include <stdexcept>
#include <string>

namespace drom {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace drom
