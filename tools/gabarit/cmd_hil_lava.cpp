// gabarit hil lava-job and gabarit hil lava-replay: the HIL on a LAVA board
// farm (docs/hil-farm.md). Nothing here is the harness's: lava-job writes a
// job and the folder it runs from, and lava-replay starts `gabarit hil run`
// behind the device's user command, with its verdicts on the board's console.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "commands.hpp"
#include "gabarit/app/args.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/hil/console_verdicts.hpp"
#include "gabarit/hil/dut.hpp"

namespace gabarit::cli {
namespace {

namespace fs = std::filesystem;

// The device types hil/lava/ defines: the HIL firmware on a QEMU Cortex-M
// board (the job deploys the firmware and the table), or a board that runs
// gabarit's board application and relay (machine null: the board holds its
// table, and the device's hardware map names its HIL link).
struct DeviceType {
  const char* name;
  const char* machine;
  const char* arch;
};
constexpr DeviceType kDeviceTypes[] = {{"gabarit-qemu-mps2-an500", "mps2-an500", "arm"},
                                       {"gabarit-qemu-mps3-an547", "mps3-an547", "arm"},
                                       {"gabarit-board", nullptr, "arm64"}};

// The options of `gabarit hil run` a job may set: data only (none names a
// program to start or a folder to write outside the job's own).
const std::set<std::string> kReplayOptions = {"--frames", "--faults", "--seed", "--rate", "--init", "--timeout"};

// A path that goes into YAML and a LAVA command line as it is: absolute, no
// spaces, quotes or shell characters.
std::string plain_absolute(const fs::path& p, const std::string& what) {
  const std::string s = fs::absolute(p).lexically_normal().string();
  for (const char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '/' || c == '.' || c == '_' || c == '-' || c == '+'))
      throw app::UsageError(what + " '" + s + "': a LAVA job needs a path of letters, digits and / . _ - + only");
  return s;
}

void copy_into(const fs::path& from, const fs::path& to) {
  if (!fs::is_regular_file(from)) throw app::UsageError(from.string() + ": no such file");
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

void write_text(const fs::path& path, const std::string& text) {
  app::OutputFile out(path.string());
  out.write(text);
  out.commit();
}

// The job's deploy and boot actions: the firmware and the table into a QEMU
// board, or (a board of its own) power it on and connect to its console.
std::string boot_actions(const DeviceType& type, const std::string& bundle, std::uint32_t slot) {
  if (type.machine == nullptr) return "- boot:\n    method: minimal\n    reset: true\n    timeout:\n      minutes: 2\n";
  char slot_hex[16];
  std::snprintf(slot_hex, sizeof slot_hex, "0x%08x", slot);
  std::ostringstream y;
  y << "- deploy:\n    timeout:\n      minutes: 2\n    to: tmpfs\n    images:\n"
    << "      firmware:\n        url: file://" << bundle << "/firmware.elf\n        image_arg: -kernel {firmware}\n"
    << "      table:\n        url: file://" << bundle << "/table.gbt\n"
    << "        image_arg: -device loader,file={table},addr=" << slot_hex << ",force-raw=on\n"
    << "- boot:\n    method: qemu\n    media: tmpfs\n    timeout:\n      minutes: 2\n";
  return y.str();
}

std::string job_yaml(const std::string& name, const DeviceType& type, const std::string& bundle, std::uint32_t slot,
                     std::uint32_t minutes) {
  std::ostringstream y;
  y << "# Written by `gabarit hil lava-job` (docs/hil-farm.md). "
    << (type.machine != nullptr ? "The board boots the HIL firmware with the\n# table in its flash slot"
                                : "The board is powered on and runs its board\n# application and relay")
    << "; the device's user command gabarit_replay starts `gabarit hil lava-replay`\n"
       "# on the worker, which replays the sequence into the board's HIL link and prints each verdict\n"
       "# on its console, where the monitors below make test cases of them.\n"
    << "device_type: " << type.name << "\n"
    << "job_name: gabarit hil " << name << " on " << (type.machine != nullptr ? type.machine : "a gabarit board") << "\n"
    << "timeouts:\n  job:\n    minutes: " << minutes + 6 << "\n  action:\n    minutes: " << minutes
    << "\n  connection:\n    minutes: 2\n"
    << "priority: medium\nvisibility: public\n"
    << "context:\n  arch: " << type.arch << "\n  gabarit_bundle: " << bundle << "\n"
    << "actions:\n"
    << boot_actions(type, bundle, slot)
    << "- command:\n    name: gabarit_replay\n    timeout:\n      minutes: 1\n"
    // The frame pattern ends at the line's end: the console reaches LAVA in
    // pieces, and a pattern ending in \w+ matches the "p" of a "px" not yet read.
    << "- test:\n    timeout:\n      minutes: " << minutes << "\n    monitors:\n"
    << "    - name: gabarit-hil-frames\n      start: '" << hil::kConsoleFramesStart << "'\n      end: '"
    << hil::kConsoleFramesEnd << "'\n"
    << "      pattern: 'gabarit-hil case=(?P<test_case_id>frame-\\d+) result=(?P<result>pass|fail|skip) "
       "measurement=(?P<measurement>[0-9.]+) units=(?P<units>\\w+)[\\r\\n]'\n"
    << "    - name: gabarit-hil-checks\n      start: '" << hil::kConsoleChecksStart << "'\n      end: '"
    << hil::kConsoleRunEnd << "'\n"
    << "      pattern: 'gabarit-hil case=(?P<test_case_id>[\\w.-]+) result=(?P<result>pass|fail)'\n";
  return y.str();
}

app::Args declare_lava_job() {
  return app::Args(
      "hil lava-job", "--sequence DIR [--firmware ELF] --out DIR [--table T] [--device-type TYPE] [--frames N] [--faults SPEC]",
      "Writes a LAVA job that runs the HIL on a board of a farm (docs/hil-farm.md), and the folder it runs from:\n"
      "OUT/job.yaml, the firmware, the table and the sequence, and OUT/replay.args (the harness's options). The\n"
      "job boots the HIL firmware with the table in its flash slot, the device's user command gabarit_replay\n"
      "starts `gabarit hil lava-replay` on the worker, and the board's console gives one LAVA test case per frame\n"
      "(bit-identical to the host's reference: pass; the position error against gt.csv as the measurement) and\n"
      "one per check. The harness's report (JUnit, CSV, Markdown) is written into OUT/report on the worker. OUT must\n"
      "be on a path the worker reads, under the same name (context gabarit_bundle); it must be new or empty.\n"
      "For the device type gabarit-board (a board running gabarit's board application and relay, e.g. the aarch64\n"
      "virtual board or a Raspberry Pi) the job powers the board on and reads its console; the board must hold the\n"
      "job's table (it is the host's reference), and there is no --firmware.",
      {{"--sequence", "DIR", "folder with frames.y4m and, optionally, gt.csv", false, true},
       {"--firmware", "ELF", "the HIL firmware for a QEMU device type's core (gabarit-firmware-hil.elf)"},
       {"--out", "DIR", "the job's folder (new or empty)", false, true},
       {"--table", "T", "the table (default DIR/table.gbt)"},
       {"--device-type", "TYPE",
        "gabarit-qemu-mps2-an500 (Cortex-M7, the default), gabarit-qemu-mps3-an547 (Cortex-M55) or gabarit-board"},
       {"--name", "NAME", "the job's name (default: the sequence folder's name)"},
       {"--minutes", "M", "the test's timeout (default 10)"},
       {"--frames", "N", "hil run --frames"},
       {"--faults", "SPEC", "hil run --faults (the harness's kinds: the board has no rig)"},
       {"--seed", "S", "hil run --seed"},
       {"--init", "X,Y[,THETA[,DEPTH]]", "hil run --init"},
       {"--timeout", "MS", "hil run --timeout"}});
}

int lava_job(const std::vector<std::string>& argv) {
  app::Args args = declare_lava_job();
  if (!args.parse(argv)) return 0;
  const fs::path sequence = args.get("--sequence");
  const fs::path out = args.get("--out");
  const std::string table = args.get_or("--table", (sequence / "table.gbt").string());
  const std::string type_name = args.get_or("--device-type", kDeviceTypes[0].name);
  const DeviceType* type = nullptr;
  for (const DeviceType& t : kDeviceTypes)
    if (type_name == t.name) type = &t;
  if (type == nullptr)
    throw app::UsageError("--device-type " + type_name + ": want gabarit-qemu-mps2-an500, gabarit-qemu-mps3-an547 or gabarit-board");
  const bool qemu = type->machine != nullptr;
  if (qemu != args.has("--firmware"))
    throw app::UsageError(qemu ? "--device-type " + type_name + " wants --firmware (the HIL firmware's ELF)"
                               : "--device-type gabarit-board takes no --firmware: the board runs its own application");
  if (!fs::exists(sequence / "frames.y4m")) throw app::UsageError(sequence.string() + ": no frames.y4m");
  const auto minutes = static_cast<std::uint32_t>(args.integer("--minutes", 10, 1, 24 * 60));
  if (!fs::is_regular_file(table)) throw app::UsageError("no table: " + table + " (give --table)");
  // On a QEMU board the table goes where the firmware's slot is, and must fit it.
  std::uint64_t slot = 0;
  if (qemu) {
    slot = hil::find_elf_symbol(args.get("--firmware"), "gabarit_table_slot").address;
    const std::uint64_t end = hil::find_elf_symbol(args.get("--firmware"), "gabarit_table_slot_end").address;
    if (end < slot || fs::file_size(table) > end - slot)
      throw app::UsageError(table + ": " + std::to_string(fs::file_size(table)) + " bytes; the firmware's table slot holds " +
                            std::to_string(end - slot));
  }
  if (fs::exists(out) && (!fs::is_directory(out) || fs::directory_iterator(out) != fs::directory_iterator()))
    throw app::UsageError(out.string() + ": exists and is not an empty folder (--out wants a new or empty one)");
  const std::string bundle = plain_absolute(out, "--out");
  std::string replay_args;
  for (const std::string& option : kReplayOptions)
    if (args.has(option)) replay_args += option + "\n" + args.get(option) + "\n";
  fs::create_directories(out / "sequence");
  copy_into(sequence / "frames.y4m", out / "sequence" / "frames.y4m");
  if (fs::exists(sequence / "gt.csv")) copy_into(sequence / "gt.csv", out / "sequence" / "gt.csv");
  copy_into(table, out / "table.gbt");
  if (qemu) copy_into(args.get("--firmware"), out / "firmware.elf");
  write_text(out / "replay.args", replay_args);
  const std::string name = args.get_or("--name", fs::absolute(sequence).lexically_normal().filename().string());
  write_text(out / "job.yaml", job_yaml(name, *type, bundle, static_cast<std::uint32_t>(slot), minutes));
  if (qemu)
    std::printf("%s/job.yaml: %s, the table at 0x%08x; run it with lava-run or submit it with lavacli\n", bundle.c_str(),
                type->name, static_cast<unsigned>(slot));
  else
    std::printf("%s/job.yaml: %s (the board must hold %s/table.gbt); run it with lava-run or submit it with lavacli\n",
                bundle.c_str(), type->name, bundle.c_str());
  return 0;
}

app::Args declare_lava_replay() {
  return app::Args(
      "hil lava-replay", "--bundle DIR (--link HOST:PORT | --board FILE) [--foreground]",
      "The host side of a LAVA job that `gabarit hil lava-job` wrote (docs/hil-farm.md): the device's user command\n"
      "gabarit_replay runs it once the board has booted. It returns at once and runs, detached from LAVA's terminal,\n"
      "`gabarit hil run --dut board:...` on the board's HIL link (a QEMU board's second UART, on a TCP port of the\n"
      "worker, or the link the board's hardware map names), with the\n"
      "job's sequence, table and options (DIR/replay.args) and --console-verdicts, its report into DIR/report and\n"
      "its output into DIR/replay.log.",
      {{"--bundle", "DIR", "the job's folder (the job's context gabarit_bundle)", false, true},
       {"--link", "HOST:PORT", "a QEMU board's HIL link (the device's second serial port, a TCP server)"},
       {"--board", "FILE", "a board's hardware map (hil/boards/*.yaml), for the device type gabarit-board"},
       {"--foreground", "", "do not detach (for a test)"}});
}

// Detaches from LAVA's pty: SIGHUP ignored (LAVA closes the pty when the
// user command returns), a new session, stdio to the log; the command
// returns only once the child is detached, so no signal can catch it halfway.
void detach(const std::string& log) {
  ::signal(SIGHUP, SIG_IGN);
  int ready[2];
  if (::pipe(ready) != 0) throw app::Error("hil lava-replay: pipe failed");
  const pid_t child = ::fork();
  if (child < 0) throw app::Error("hil lava-replay: fork failed");
  if (child > 0) {
    char byte = 0;
    ::close(ready[1]);
    const bool detached = ::read(ready[0], &byte, 1) == 1;
    ::_exit(detached ? 0 : 1);
  }
  ::close(ready[0]);
  ::setsid();
  const int in = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (in < 0 || out < 0) ::_exit(2);
  ::dup2(in, 0);
  ::dup2(out, 1);
  ::dup2(out, 2);
  const char byte = 1;
  if (::write(ready[1], &byte, 1) != 1) ::_exit(2);
  ::close(ready[1]);
}

int lava_replay(const std::vector<std::string>& argv) {
  app::Args args = declare_lava_replay();
  if (!args.parse(argv)) return 0;
  const fs::path bundle = fs::absolute(args.get("--bundle"));
  if (args.has("--link") == args.has("--board")) throw app::UsageError("give one of --link HOST:PORT and --board FILE");
  const std::string link = args.get_or("--link", "");
  const bool host_port = link.find(':') != std::string::npos && link.find_first_of(" \t\n") == std::string::npos;
  if (args.has("--link") && !host_port) throw app::UsageError("--link " + link + ": want HOST:PORT");
  if (args.has("--board") && !fs::is_regular_file(args.get("--board")))
    throw app::UsageError("--board " + args.get("--board") + ": no such file");
  const fs::path board = args.has("--board") ? fs::absolute(args.get("--board")) : bundle / "board.yaml";
  for (const char* file : {"job.yaml", "table.gbt", "replay.args", "sequence/frames.y4m"})
    if (!fs::exists(bundle / file)) throw app::UsageError(bundle.string() + ": no " + file + " (not a folder hil lava-job wrote)");
  std::vector<std::string> run = {"run", "--dut", "board:" + board.string(), "--sequence",
                                  (bundle / "sequence").string(), "--table", (bundle / "table.gbt").string(),
                                  "--report", (bundle / "report").string(), "--console-verdicts"};
  std::ifstream options(bundle / "replay.args");
  for (std::string option, value; std::getline(options, option) && std::getline(options, value);) {
    if (!kReplayOptions.count(option)) throw app::UsageError(bundle.string() + "/replay.args: " + option + " is not an option a job sets");
    run.push_back(option);
    run.push_back(value);
  }
  if (args.has("--link"))
    write_text(board, "# Written by gabarit hil lava-replay: the LAVA device's HIL link.\nname: lava-board\n"
                      "description: a LAVA device's board, its HIL link on its second UART\nrelay: tcp:" +
                          link + "\nhang_timeout_ms: 60000\n");
  if (!args.has("--foreground")) detach((bundle / "replay.log").string());
  return hil(run);
}

}  // namespace

int hil_lava(const std::string& verb, const std::vector<std::string>& argv) {
  return verb == "lava-job" ? lava_job(argv) : lava_replay(argv);
}

}  // namespace gabarit::cli
