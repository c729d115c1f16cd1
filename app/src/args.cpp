#include "gabarit/app/args.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace gabarit::app {

Args::Args(std::string command, std::string synopsis, std::string description, std::vector<Option> options,
           std::string positional_name)
    : command_(std::move(command)), synopsis_(std::move(synopsis)), description_(std::move(description)),
      positional_name_(std::move(positional_name)), options_(std::move(options)) {}

const Option* Args::find(const std::string& name) const {
  for (const Option& o : options_)
    if (o.name == name) return &o;
  return nullptr;
}

bool Args::parse(const std::vector<std::string>& argv) {
  for (std::size_t i = 0; i < argv.size(); ++i) {
    std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(help().c_str(), stdout);
      return false;
    }
    if (a.size() > 1 && a[0] == '-' && !(a.size() > 1 && (std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '.'))) {
      std::string value;
      bool inline_value = false;
      if (const std::size_t eq = a.find('='); eq != std::string::npos) {
        value = a.substr(eq + 1);
        a = a.substr(0, eq);
        inline_value = true;
      }
      const Option* o = find(a);
      if (!o) throw UsageError("unknown option " + a);
      if (o->value_name.empty()) {
        if (inline_value) throw UsageError(a + " takes no value");
        values_[a].push_back("1");
      } else {
        if (!inline_value) {
          if (i + 1 >= argv.size()) throw UsageError(a + " needs a value " + o->value_name);
          value = argv[++i];
        }
        if (!o->repeatable && has(a)) throw UsageError(a + " given twice");
        values_[a].push_back(value);
      }
    } else {
      if (positional_name_.empty()) throw UsageError("unexpected argument '" + a + "'");
      positionals_.push_back(a);
    }
  }
  for (const Option& o : options_)
    if (o.required && !has(o.name)) throw UsageError("missing required option " + o.name + " " + o.value_name);
  return true;
}

const std::string& Args::get(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end()) throw UsageError("missing option " + name);
  return it->second.front();
}

std::string Args::get_or(const std::string& name, const std::string& fallback) const {
  return has(name) ? get(name) : fallback;
}

const std::vector<std::string>& Args::all(const std::string& name) const {
  static const std::vector<std::string> none;
  const auto it = values_.find(name);
  return it == values_.end() ? none : it->second;
}

double Args::number(const std::string& name, double fallback, double lo, double hi) const {
  if (!has(name)) return fallback;
  const std::string& s = get(name);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end || !std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream m;
    m << name << " '" << s << "': want a number in [" << lo << ", " << hi << "]";
    throw UsageError(m.str());
  }
  return v;
}

std::int64_t Args::integer(const std::string& name, std::int64_t fallback, std::int64_t lo, std::int64_t hi) const {
  if (!has(name)) return fallback;
  const std::string& s = get(name);
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || *end || errno != 0 || v < lo || v > hi) {
    throw UsageError(name + " '" + s + "': want an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return v;
}

std::string Args::help() const {
  std::ostringstream o;
  // A subcommand ("track") or a program of its own ("gabarit-board").
  const std::string program = command_.rfind("gabarit", 0) == 0 ? command_ : "gabarit " + command_;
  o << "usage: " << program << " " << synopsis_ << "\n\n" << description_ << "\n\noptions:\n";
  for (const Option& opt : options_) {
    std::string left = "  " + opt.name + (opt.value_name.empty() ? "" : " " + opt.value_name);
    if (left.size() < 26) left.resize(26, ' ');
    else left += "\n" + std::string(26, ' ');
    // Continuation lines of a help text line up under its first line.
    std::string text;
    for (std::size_t at = 0, next = 0; at <= opt.help.size(); at = next + 1) {
      next = opt.help.find('\n', at);
      if (next == std::string::npos) next = opt.help.size();
      std::string line = opt.help.substr(at, next - at);
      if (at > 0) {
        line.erase(0, line.find_first_not_of(' ') == std::string::npos ? line.size() : line.find_first_not_of(' '));
        text += "\n" + std::string(26, ' ');
      }
      text += line;
    }
    o << left << text << (opt.required ? " (required)" : "") << "\n";
  }
  o << "  --help                  show this help\n";
  return o.str();
}

std::vector<double> parse_number_list(const std::string& text, const std::string& what, std::size_t min_count,
                                      std::size_t max_count) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end || !std::isfinite(v)) throw UsageError(what + " '" + text + "': '" + item + "' is not a number");
    out.push_back(v);
  }
  if (out.size() < min_count || out.size() > max_count) {
    throw UsageError(what + " '" + text + "': want " + std::to_string(min_count) + " to " + std::to_string(max_count) + " comma-separated numbers");
  }
  return out;
}

Pose parse_init_pose(const std::string& text, const TableView& table, const std::string& what) {
  const auto init = parse_number_list(text, what, 2, 4);
  for (std::size_t i = 0; i < init.size() && i < 3; ++i)
    if (std::fabs(init[i]) > 1e5) throw UsageError(what + ": values must lie within +-100000");
  Pose pose{static_cast<float>(init[0]), static_cast<float>(init[1]), init.size() > 2 ? static_cast<float>(init[2]) : 0.0f, 0};
  if (init.size() > 3) {
    if (init[3] < 0 || init[3] >= table.depth_count() || init[3] != std::floor(init[3])) {
      throw UsageError(what + ": DEPTH must be an integer in 0.." + std::to_string(table.depth_count() - 1));
    }
    pose.depth = static_cast<std::uint16_t>(init[3]);
  }
  return pose;
}

FrameSize parse_size(const std::string& text, const std::string& what, std::uint32_t min_side, std::uint32_t max_side) {
  unsigned long long w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%llux%llu%c", &w, &h, &tail) != 2 || w < min_side || h < min_side || w > max_side ||
      h > max_side || text.find('-') != std::string::npos) {
    throw UsageError(what + " '" + text + "': want WxH with " + std::to_string(min_side) + " <= W,H <= " +
                     std::to_string(max_side));
  }
  return {static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h)};
}

VoterChoice parse_voter(const std::string& text, const std::string& what) {
  if (text == "auto") return VoterChoice::kAuto;
  if (text == "csr") return VoterChoice::kCsr;
  if (text == "dense") return VoterChoice::kDense;
  throw UsageError(what + " '" + text + "': want auto, csr or dense");
}

}  // namespace gabarit::app
