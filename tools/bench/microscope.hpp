// The 4-DOF microscope experiment (thesis section 6.1), re-measured on the
// grayscale scene of `gabarit synth --scene microscope`: accuracy and
// per-frame time of the tracker (plain, refined, motion filter + recovery)
// against OpenCV's exhaustive NCC over the same 4-DOF window, the speed-up of
// multi-threaded voting, and the time to build a ~1000-feature 4-DOF table.
#pragma once

#include <string>

namespace gabarit::bench {

// Writes DIR/microscope.md (and CSV/SVG files beside it); returns the exit code.
int run_microscope(const std::string& dir, bool quick);

}  // namespace gabarit::bench
