// Host tools (table builder, CLI, synthetic sequences) report failures as one
// exception type carrying a message that names the offending file and field;
// the CLI catches it at the top, prints it to stderr and exits non-zero. The
// kernel itself never throws: its errors are gabarit::Status values.
#pragma once

#include <stdexcept>
#include <string>

namespace gabarit::app {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace gabarit::app
