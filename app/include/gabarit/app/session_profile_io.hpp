// The session profile (session_profile.hpp) for hosted programs: its text
// file, and the command-line option group every program that runs a session
// declares (gabarit track, gabarit-board), read and validated in one place.
//
// The text file (docs/file-formats.md, "Session profile"):
//   gabarit-session-profile 1
//   # a comment
//   recovery = detect
//   search-budget = 40
// One `key = value` a line, keys as the options' names without the dashes;
// a key left out keeps its default; an unknown key, a repeated key or a bad
// value is an error naming the file and line.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "gabarit/app/args.hpp"
#include "gabarit/app/session_profile.hpp"

namespace gabarit::app {

inline constexpr std::string_view kProfileMagic = "gabarit-session-profile 1";

// The text of a profile: every key, in a fixed order (same profile, same bytes).
std::string format_profile(const SessionProfile& profile);
// Parses a profile's text; throws app::Error naming `origin` and the line.
// The result is validated (validate()).
SessionProfile parse_profile(std::string_view text, const std::string& origin);
// Reads a profile file (read_profile) or writes one (through OutputFile).
SessionProfile read_profile(const std::string& path);

// "modes,reinit" -> the kImprove* bits; throws UsageError naming `what`.
std::uint32_t parse_improvements_off(const std::string& list, const std::string& what);
std::string improvements_off_list(std::uint32_t off);  // "" for none

// The options every session-running program declares, for its Args.
std::vector<Option> session_option_group();
// The profile the options in `args` describe (those of session_option_group()
// present), over `--profile FILE` when given, validated once. Throws
// UsageError naming the option.
SessionProfile read_session_profile(const Args& args);

}  // namespace gabarit::app
