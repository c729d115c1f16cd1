// gabarit — the host CLI: table building and inspection, synthetic sequences,
// tracking and evaluation. Errors go to stderr with a non-zero exit code
// (2 for bad usage, 1 for everything else).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <exception>
#include <string>
#include <vector>

#include "gabarit/app/args.hpp"
#include "commands.hpp"

namespace {

constexpr const char* kUsage =
    "usage: gabarit <command> [options]   (gabarit <command> --help for each)\n\n"
    "commands:\n"
    "  tables build     build a stencil look-up table from a model and a motion space\n"
    "  tables inspect   validate a table and print it as JSON\n"
    "  tables analyse   margins of error, robustness and overlap of a table (JSON, SVG)\n"
    "  tables export-hdl  memory images and a package for the hardware voter\n"
    "  synth            write a synthetic sequence with ground truth\n"
    "  detect           find a model anywhere in an image or in each frame of a sequence\n"
    "  track            track a model through a sequence\n"
    "  eval             compare tracked poses with ground truth\n"
    "  vectors          write the cross-target test vectors (table, frames, expected results)\n"
    "  hil run          replay a sequence into a device under test, check and report (HIL)\n"
    "  hil lava-job     write a LAVA job that runs the HIL on a board farm (docs/hil-farm.md)\n"
    "  bench            re-measure the thesis's synthetic experiments (runs gabarit-bench)\n";

// `gabarit bench` runs gabarit-bench from this executable's directory: the
// benchmark links OpenCV (the peer it measures against), this binary never does.
int exec_bench(char** argv) {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::string bench = (ec ? std::filesystem::path(".") : self.parent_path()) / "gabarit-bench";
  argv[1] = const_cast<char*>(bench.c_str());
  ::execv(bench.c_str(), argv + 1);
  std::fprintf(stderr, "gabarit bench: cannot run %s: %s (built only when libopencv-imgproc-dev is installed)\n", bench.c_str(),
               std::strerror(errno));
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string command;
  try {
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
      std::fputs(kUsage, args.empty() ? stderr : stdout);
      return args.empty() ? 2 : 0;
    }
    command = args[0];
    args.erase(args.begin());
    if (command == "bench") return exec_bench(argv);
    if (command == "tables") {
      if (args.empty()) throw gabarit::app::UsageError("tables: want 'build', 'inspect', 'analyse' or 'export-hdl'");
      const std::string sub = args[0];
      args.erase(args.begin());
      command += " " + sub;
      if (sub == "build") return gabarit::cli::tables_build(args);
      if (sub == "inspect") return gabarit::cli::tables_inspect(args);
      if (sub == "analyse" || sub == "analyze") return gabarit::cli::tables_analyse(args);
      if (sub == "export-hdl") return gabarit::cli::tables_export_hdl(args);
      throw gabarit::app::UsageError("tables: unknown subcommand '" + sub + "' (want build, inspect, analyse or export-hdl)");
    }
    if (command == "synth") return gabarit::cli::synth(args);
    if (command == "detect") return gabarit::cli::detect(args);
    if (command == "track") return gabarit::cli::track(args);
    if (command == "eval") return gabarit::cli::eval(args);
    if (command == "vectors") return gabarit::cli::vectors(args);
    if (command == "hil") {
#if GABARIT_HAVE_HIL
      if (!args.empty() && args[0] == "run") command += " run";
      return gabarit::cli::hil(args);
#else
      throw gabarit::app::Error("hil: this build has no HIL harness (it is built for the host only)");
#endif
    }
    throw gabarit::app::UsageError("unknown command '" + command + "'");
  } catch (const gabarit::app::UsageError& e) {
    std::fprintf(stderr, "gabarit %s: %s\n(see gabarit %s --help)\n", command.c_str(), e.what(),
                 command.empty() ? "" : command.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gabarit %s: error: %s\n", command.c_str(), e.what());
    return 1;
  }
}
