#include "gabarit/hil/board_map.hpp"

#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#ifdef GABARIT_HAVE_LINK_USB
#include "gabarit/link/usb_host.hpp"
#endif

namespace gabarit::hil {

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

long number(const std::string& v, long lo, long hi, const std::string& where, const std::string& key) {
  char* end = nullptr;
  const long n = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || n < lo || n > hi)
    throw app::Error(where + ": " + key + " '" + v + "': want a whole number in " + std::to_string(lo) + ".." + std::to_string(hi));
  return n;
}

}  // namespace

BoardMap parse_board_map(const std::string& text, const std::string& where_file) {
  BoardMap m;
  m.source = where_file;
  std::istringstream in(text);
  std::string line, section;
  for (int number_of_line = 1; std::getline(in, line); ++number_of_line) {
    const std::string where = where_file + ":" + std::to_string(number_of_line);
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    if (trim(line).empty()) continue;
    const std::size_t indent = line.find_first_not_of(' ');
    if (line.find('\t') != std::string::npos) throw app::Error(where + ": tabs are not YAML indentation");
    const auto colon = line.find(':');
    if (colon == std::string::npos) throw app::Error(where + ": want 'key: value'");
    const std::string key = trim(line.substr(0, colon));
    std::string value = trim(line.substr(colon + 1));
    if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') && value.back() == value.front())
      value = value.substr(1, value.size() - 2);
    if (indent == 0) {
      section.clear();
      if (value.empty()) {
        if (key != "gpio") throw app::Error(where + ": '" + key + "' is not a section (the only one is gpio)");
        section = key;
        continue;
      }
    } else if (indent != 2 || section.empty()) {
      throw app::Error(where + ": indentation: two spaces, and only under a section");
    }
    const std::string full = section.empty() ? key : section + "." + key;
    if (full == "name") m.name = value;
    else if (full == "description") m.description = value;
    else if (full == "relay") m.relay = value;
    else if (full == "baud") m.baud = static_cast<std::uint32_t>(number(value, 1200, 4000000, where, full));
    else if (full == "usb") {
#ifdef GABARIT_HAVE_LINK_USB
      link::UsbIdentity id;
      std::string error;
      if (!link::parse_usb_identity(value, id, error)) throw app::Error(where + ": usb " + error);
#endif
      m.usb = value;
    } else if (full == "gpio.chip") m.gpio_chip = value;
    else if (full == "gpio.lock") m.lock_line = static_cast<int>(number(value, 0, 65535, where, full));
    else if (full == "gpio.strobe") m.strobe_line = static_cast<int>(number(value, 0, 65535, where, full));
    else if (full == "camera") m.camera = value;
    else if (full == "frame_path") {
      if (value != "vivid") throw app::Error(where + ": frame_path '" + value + "': the only one is vivid (docs/hil-boards.md)");
      m.frame_path = value;
    } else if (full == "hang_timeout_ms") m.hang_timeout_ms = static_cast<std::uint32_t>(number(value, 100, 3600000, where, full));
    else throw app::Error(where + ": unknown key '" + full + "'");
  }
  if (m.name.empty()) throw app::Error(where_file + ": no name");
  if (m.relay.empty()) throw app::Error(where_file + ": no relay (a serial device, or tcp:HOST:PORT)");
  return m;
}

BoardMap load_board_map(const std::string& name_or_path, const std::string& boards_dir) {
  const bool yaml = name_or_path.size() > 5 && name_or_path.compare(name_or_path.size() - 5, 5, ".yaml") == 0;
  const bool is_path = name_or_path.find('/') != std::string::npos || yaml;
  const std::string path = is_path ? name_or_path : boards_dir + "/" + name_or_path + ".yaml";
  if (!std::filesystem::exists(path))
    throw app::Error(path + ": no such board map" + (is_path ? "" : " (hil/boards/ lists the boards)"));
  return parse_board_map(app::read_text(path, 1u << 20), path);
}

}  // namespace gabarit::hil
