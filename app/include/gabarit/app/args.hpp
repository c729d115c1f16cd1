// A small command-line parser for the gabarit subcommands: --name VALUE or
// --name=VALUE, flags, repeatable options, positionals, and --help text built
// from the same option list that is parsed (so the help cannot go stale).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "gabarit/app/error.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit::app {

// Bad usage: the CLI prints the message and the usage line, exit code 2.
class UsageError : public app::Error {
 public:
  using app::Error::Error;
};

struct Option {
  std::string name;        // "--x" or "-o"
  std::string value_name;  // empty for a flag
  std::string help;
  bool repeatable = false;
  bool required = false;
};

class Args {
 public:
  Args(std::string command, std::string synopsis, std::string description, std::vector<Option> options,
       std::string positional_name = {});

  // Declares one more option (an option group shared by several programs,
  // such as session_profile_io.hpp's), before parse().
  void add(Option option) { options_.push_back(std::move(option)); }

  // Returns false after printing help (the caller exits 0).
  bool parse(const std::vector<std::string>& argv);

  bool has(const std::string& name) const { return values_.count(name) != 0; }
  const std::string& get(const std::string& name) const;
  std::string get_or(const std::string& name, const std::string& fallback) const;
  const std::vector<std::string>& all(const std::string& name) const;
  const std::vector<std::string>& positionals() const { return positionals_; }

  double number(const std::string& name, double fallback, double lo, double hi) const;
  std::int64_t integer(const std::string& name, std::int64_t fallback, std::int64_t lo, std::int64_t hi) const;
  std::string help() const;

 private:
  const Option* find(const std::string& name) const;
  std::string command_, synopsis_, description_, positional_name_;
  std::vector<Option> options_;
  std::map<std::string, std::vector<std::string>> values_;
  std::vector<std::string> positionals_;
};

// Parses "A,B" or "A,B,C[,D]" into numbers; throws UsageError naming `what`.
std::vector<double> parse_number_list(const std::string& text, const std::string& what, std::size_t min_count,
                                      std::size_t max_count);

// "X,Y[,THETA[,DEPTH]]": the pose before the first frame; DEPTH must be one
// of the table's depths. Throws UsageError naming `what`.
Pose parse_init_pose(const std::string& text, const TableView& table, const std::string& what);

struct FrameSize {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
};
// "WxH" with min_side <= W, H <= max_side. Throws UsageError naming `what`.
FrameSize parse_size(const std::string& text, const std::string& what, std::uint32_t min_side, std::uint32_t max_side);

// "auto", "csr" or "dense". Throws UsageError naming `what`.
VoterChoice parse_voter(const std::string& text, const std::string& what);

}  // namespace gabarit::app
