// gabarit hil run
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <optional>

#include "commands.hpp"
#include "gabarit/app/args.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/session_profile_io.hpp"
#include "gabarit/hil/board_map.hpp"
#include "gabarit/hil/console_verdicts.hpp"
#include "gabarit/hil/dut.hpp"
#include "gabarit/hil/harness.hpp"
#include "gabarit/hil/report.hpp"

namespace gabarit::cli {
namespace {

std::string beside_this_program(const std::string& name) {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ((ec ? std::filesystem::path(".") : self.parent_path()) / name).string();
}

struct SequenceShape {
  std::uint32_t frames = 0, width = 0, height = 0;
};
SequenceShape sequence_shape(const std::string& path) {
  auto frames = app::open_frames(path);
  app::GrayImage image;
  SequenceShape s;
  while (frames->next(image)) {
    if (s.frames++ == 0) s.width = image.width, s.height = image.height;
  }
  return s;
}

// A report folder is written into only if it is new, empty, or a previous
// run's report (which it replaces file by file): never over other files.
void prepare_report_dir(const std::string& dir) {
  namespace fs = std::filesystem;
  if (!fs::exists(dir)) {
    fs::create_directories(dir);
    return;
  }
  if (!fs::is_directory(dir)) throw app::Error(dir + ": not a directory (--report wants a folder)");
  const bool empty = fs::directory_iterator(dir) == fs::directory_iterator();
  if (!empty && !fs::exists(fs::path(dir) / "summary.json") && !fs::exists(fs::path(dir) / "results.jsonl"))
    throw app::Error(dir + ": holds files that are not a HIL report; give a new or empty folder");
  fs::remove(fs::path(dir) / "results.jsonl");
  fs::remove(fs::path(dir) / "dut.log");  // the DUT's log is appended to across its restarts in a run
}

app::Args declare_hil_run() {
  return app::Args(
      "hil run",
      "--dut inprocess|verilator|cortex-m|virtual-board|board:NAME --sequence DIR --report DIR [--table T] [--init X,Y[,THETA[,DEPTH]]] [--rate FPS]\n"
      "       [--faults FILE|random:P|cycle:N:KINDS] [--frames N] [--seed S] [--soak N]",
      "Replays a recorded sequence (DIR/frames.y4m, DIR/gt.csv if any) into a device under test over the HIL link\n"
      "(docs/hil-protocol.md), collects every pose, accounts for every frame (a pose, or why not), checks each pose\n"
      "bit for bit against the host's own tracking of the same frames with the same table, injects faults on the\n"
      "host side of the link, and writes a report: frames.csv, poses.csv, results.jsonl, summary.json, junit.xml,\n"
      "faults.csv (the plan, to replay), report.md with SVG plots. Exit status 0 when every check passes, 1 otherwise.\n"
      "DUTs: inprocess (the session profile's tracker on a thread, loopback or UDP link), verilator (the hardware\n"
      "voter, Verilated, in gabarit-hil-verilator: the thesis's loop with the voter in RTL), cortex-m (the HIL\n"
      "firmware in qemu-system-arm, the table loaded into its flash slot, its UART0 on a socket), virtual-board (the\n"
      "board application on Debian's arm64 kernel in qemu-system-aarch64: frames through vivid and V4L2, poses over a\n"
      "USB FunctionFS gadget, GPIO through gpio-sim, bridged by a relay in the guest on a virtio-serial port),\n"
      "board:NAME (a real board running the same relay, from hil/boards/NAME.yaml or a .yaml path; docs/hil-boards.md).",
      {{"--dut", "KIND", "inprocess, verilator, cortex-m, virtual-board or board:NAME", false, true},
       {"--sequence", "DIR", "folder with frames.y4m and, optionally, gt.csv (gabarit synth writes both)", false, true},
       {"--report", "DIR", "folder for the report (new, empty, or a previous report)", false, true},
       {"--table", "T", "the table (default DIR/table.gbt); the DUT must hold the same (HELLO carries its CRC)"},
       {"--init", "X,Y[,THETA[,DEPTH]]", "the pose before the first frame (default: gt.csv's first row)"},
       {"--rate", "FPS", "send frames at this rate, dropping those the DUT is too busy for (default: as fast as it takes them)"},
       {"--faults", "SPEC", "faults to inject: a plan file (FRAME KIND per line; see faults.csv of a run), random:P (a\n"
                            "                          fraction P of the frames, the harness's kinds drawn at random) or\n"
                            "                          cycle:N:KIND,KIND,... (one every N frames, the kinds in turn; the rig's\n"
                            "                          kinds, e.g. board-kill, need a DUT with a rig: virtual-board)"},
       {"--frames", "N", "the first N frames only"},
       {"--seed", "S", "the random fault plan's and each fault's bytes and bits (default 1)"},
       {"--soak", "N", "play the sequence N times over (frame k is frame k mod its length): soak.csv samples the\n"
                       "                          host's and the DUT's resident memory and the latency every --soak-window frames"},
       {"--soak-window", "F", "with --soak: frames per sample (default 1000)"},
       {"--plain", "", "inprocess: the thesis's loop instead of the session defaults"},
       {"--profile", "FILE", "inprocess, virtual-board: the session profile the device runs (docs/file-formats.md; e.g.\n"
                             "                          tracker = particle)"},
       {"--link", "loopback|udp", "inprocess: the link (default loopback; udp: two sockets on 127.0.0.1)"},
       {"--slots", "N", "inprocess: frames the DUT queues, 1..8 (default 4)"},
       {"--firmware", "ELF", "cortex-m: the HIL firmware (build/cortex-m7/platform/cortex-m/gabarit-firmware-hil.elf)"},
       {"--machine", "NAME", "cortex-m: the QEMU board, mps2-an500 (default) or mps3-an547"},
       {"--icount", "N", "cortex-m: QEMU -icount shift=N,sleep=off (default 0: a guest instruction is 1 ns;\n"
                          "                          -1: no -icount, guest time then follows the host's)"},
       {"--verilator-dut", "PATH", "verilator: the DUT program (default: gabarit-hil-verilator beside gabarit)"},
       {"--clock-mhz", "F", "verilator: the voter's clock for times (default 48: the UP5K's lowest Fmax over seeds)"},
       {"--virtual-board", "DIR", "virtual-board: the aarch64 build (default: build/aarch64 beside this build), with\n"
                                  "                          gabarit-board, gabarit-hil-relay and virtual-board/cache (prepare.sh)"},
       {"--timeout", "MS", "declare the DUT hung after this long without an answer to a PING (default per DUT)"},
       {"--console-verdicts", "", "send each frame's verdict, then the checks, to the DUT's console as NOTEs (a board\n"
                                  "                          farm that reads the console makes test cases of them; docs/hil-farm.md)"}});
}

// The device under test `--dut KIND` names, with its options.
std::unique_ptr<hil::DutDriver> make_dut(const app::Args& args, const std::string& kind, const std::string& table,
                                         const std::string& report, const SequenceShape& shape, const std::string& frames_path) {
  std::unique_ptr<hil::DutDriver> dut;
  const std::chrono::milliseconds timeout(args.integer("--timeout", 0, 1, 3600000));
  if (kind == "inprocess") {
    hil::InprocessOptions o;
    o.table_path = table;
    if (args.has("--profile")) o.profile = app::read_profile(args.get("--profile"));
    if (args.has("--plain")) o.profile = app::plain_profile();
    o.frame_slots = static_cast<std::uint32_t>(args.integer("--slots", 4, 1, 8));
    const std::string link = args.get_or("--link", "loopback");
    if (link != "loopback" && link != "udp") throw app::UsageError("--link '" + link + "': want loopback or udp");
    o.udp = link == "udp";
    dut = hil::make_inprocess_dut(o);
  } else if (kind == "verilator") {
    const std::string program = args.get_or("--verilator-dut", beside_this_program("gabarit-hil-verilator"));
    if (::access(program.c_str(), X_OK) != 0)
      throw app::Error(program + ": not found (built with Verilator installed; or give --verilator-dut)");
    const double mhz = args.number("--clock-mhz", 48, 0.001, 10000);
    dut = hil::make_process_dut("verilator", {program, "--table", table, "--clock-hz", std::to_string(static_cast<long>(mhz * 1e6))},
                                (std::filesystem::path(report) / "dut.log").string(),
                                timeout.count() ? timeout : std::chrono::milliseconds(20000));
  } else if (kind == "cortex-m") {
    if (!args.has("--firmware")) throw app::UsageError("--dut cortex-m needs --firmware ELF (gabarit-firmware-hil.elf)");
    hil::QemuOptions o;
    o.firmware = args.get("--firmware");
    o.machine = args.get_or("--machine", "mps2-an500");
    if (o.machine != "mps2-an500" && o.machine != "mps3-an547") throw app::UsageError("--machine: want mps2-an500 or mps3-an547");
    o.icount_shift = static_cast<int>(args.integer("--icount", 0, -1, 10));
    o.table_path = table;
    o.log_path = (std::filesystem::path(report) / "dut.log").string();
    dut = hil::make_qemu_dut(o);
  } else if (kind == "virtual-board") {
    hil::VirtualBoardOptions o;
    const std::string build = args.get_or("--virtual-board", beside_this_program("../../aarch64"));
    o.cache = build + "/virtual-board/cache";
    o.board = build + "/platform/linux/gabarit-board";
    o.relay = build + "/platform/linux/gabarit-hil-relay";
    o.scripts = GABARIT_VIRTUAL_BOARD_SCRIPTS;
    o.table_path = table;
    o.window = std::to_string(shape.width) + "x" + std::to_string(shape.height);
    if (shape.width > 720 || shape.height > 480)
      throw app::UsageError(frames_path + ": " + o.window + " frames; the virtual board's camera (vivid, S-Video) is 720x480");
    o.log_path = (std::filesystem::path(report) / "dut.log").string();
    if (args.has("--profile")) {
      (void)app::read_profile(args.get("--profile"));  // refused here, not after the board has booted
      o.profile_path = args.get("--profile");
    }
    dut = hil::make_virtual_board_dut(o);
  } else if (kind.rfind("board:", 0) == 0) {
    dut = hil::make_board_dut(hil::load_board_map(kind.substr(6), GABARIT_BOARDS_DIR));
  } else {
    throw app::UsageError("--dut '" + kind + "': want inprocess, verilator, cortex-m, virtual-board or board:NAME");
  }
  if (timeout.count() != 0 && kind != "verilator") dut->set_hang_timeout(timeout);
  return dut;
}

// gt.csv's poses, if any, repeated for every loop of a soak.
std::vector<app::PoseSample> read_truth(const std::string& sequence, const hil::RunConfig& config) {
  std::vector<app::PoseSample> truth;
  if (const auto gt = std::filesystem::path(sequence) / "gt.csv"; std::filesystem::exists(gt)) truth = app::read_pose_csv(gt.string());
  if (config.loops > 1) {  // a soak's loop L shows frame k as frame L * length + k
    const std::vector<app::PoseSample> once = truth;
    for (std::uint32_t loop = 1; loop < config.loops; ++loop)
      for (app::PoseSample t : once)
        if (t.frame < config.max_frames) {
          t.frame += loop * config.max_frames;
          truth.push_back(t);
        }
  }
  return truth;
}

// The failed checks (the first ten) and a summary line; the exit status.
int summarise(const hil::RunResult& result, const std::string& report) {
  std::size_t failed = 0;
  for (const hil::Check& c : hil::run_checks(result)) {
    if (c.passed) continue;
    if (failed++ < 10) std::fprintf(stderr, "hil: FAIL %s: %s\n", c.name.c_str(), c.message.c_str());
  }
  std::size_t poses = 0;
  for (const auto& r : result.frames) poses += r.pose.has_value();
  std::fprintf(stderr, "hil: %s: %u frames, %zu poses, %zu faults injected, %zu checks failed; report in %s\n", result.caps.kind,
               result.frames_total, poses, result.faults.size(), failed, report.c_str());
  if (!result.error.empty()) std::fprintf(stderr, "hil: the run stopped: %s\n", result.error.c_str());
  return failed == 0 ? 0 : 1;
}

}  // namespace

int hil(const std::vector<std::string>& argv) {
  if (!argv.empty() && (argv[0] == "lava-job" || argv[0] == "lava-replay"))
    return hil_lava(argv[0], std::vector<std::string>(argv.begin() + 1, argv.end()));
  if (argv.empty() || (argv[0] != "run" && argv[0] != "--help" && argv[0] != "-h"))
    throw app::UsageError("hil: want 'run', 'lava-job' or 'lava-replay' (gabarit hil run --help)");
  const std::vector<std::string> rest(argv.begin() + (argv[0] == "run" ? 1 : 0), argv.end());
  app::Args args = declare_hil_run();
  if (!args.parse(rest)) return 0;
  const std::string kind = args.get("--dut");
  const std::string sequence = args.get("--sequence");
  const std::string report = args.get("--report");
  const std::string table = args.get_or("--table", (std::filesystem::path(sequence) / "table.gbt").string());
  if (!std::filesystem::exists(table)) throw app::UsageError("no table: " + table + " does not exist (give --table)");
  const std::string frames_path = (std::filesystem::path(sequence) / "frames.y4m").string();
  if (!std::filesystem::exists(frames_path)) throw app::UsageError(sequence + ": no frames.y4m");
  const auto dut_only = [&](const char* option, const char* dut) {
    if (args.has(option) && kind != dut) throw app::UsageError(std::string(option) + " applies to --dut " + dut);
  };
  dut_only("--plain", "inprocess");
  if (args.has("--profile") && kind != "inprocess" && kind != "virtual-board")
    throw app::UsageError("--profile applies to --dut inprocess and virtual-board");
  dut_only("--link", "inprocess");
  dut_only("--slots", "inprocess");
  dut_only("--firmware", "cortex-m");
  dut_only("--machine", "cortex-m");
  dut_only("--icount", "cortex-m");
  dut_only("--verilator-dut", "verilator");
  dut_only("--clock-mhz", "verilator");
  dut_only("--virtual-board", "virtual-board");

  hil::RunConfig config;
  config.sequence_dir = sequence;
  config.table_path = table;
  if (args.has("--init")) {
    const app::TableFile t(table);
    config.init = app::parse_init_pose(args.get("--init"), t.view(), "--init");
  }
  config.rate_fps = args.number("--rate", 0, 0.001, 100000);
  config.seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0, INT64_MAX));
  const SequenceShape shape = sequence_shape(frames_path);
  const std::uint32_t available = shape.frames;
  config.max_frames = static_cast<std::uint32_t>(args.integer("--frames", available, 1, 0xFFFFFFFEll));
  if (config.max_frames > available) config.max_frames = available;
  if (config.max_frames == 0) throw app::Error(frames_path + ": no frames");
  config.loops = static_cast<std::uint32_t>(args.integer("--soak", 1, 1, 1000000));
  config.soak_window = static_cast<std::uint32_t>(args.integer("--soak-window", 1000, 10, 100000000));
  if (args.has("--soak-window") && !args.has("--soak")) throw app::UsageError("--soak-window needs --soak");
  if (std::uint64_t{config.max_frames} * config.loops > 0xFFFFFFFEull) throw app::UsageError("--soak: too many frames in all");
  const std::uint32_t total_frames = config.max_frames * config.loops;
  if (args.has("--faults")) config.faults = hil::parse_fault_plan(args.get("--faults"), total_frames, config.seed);
  for (const hil::PlannedFault& f : config.faults.faults)
    if (hil::is_rig_fault(f.kind) && kind != "virtual-board" && kind.rfind("board:", 0) != 0)
      throw app::UsageError(std::string("--faults: ") + hil::fault_name(f.kind) +
                            " is a rig's fault: --dut virtual-board or board:NAME injects it");

  std::unique_ptr<hil::DutDriver> dut = make_dut(args, kind, table, report, shape, frames_path);

  prepare_report_dir(report);
  app::OutputFile jsonl((std::filesystem::path(report) / "results.jsonl").string());
  std::FILE* stream = jsonl.stream();
  config.on_resolved = [&](const hil::FrameRecord& r) {
    std::fputs((hil::frame_json(r) + "\n").c_str(), stream);
    std::fflush(stream);
  };
  const bool tty = ::isatty(2) != 0;
  config.progress = [&](std::uint32_t done, std::uint32_t total) {
    std::fprintf(stderr, tty ? "\rhil: %u/%u frames answered" : "hil: %u/%u frames answered\n", done, total);
    if (tty && done == total) std::fputc('\n', stderr);
  };
  const std::vector<app::PoseSample> truth = read_truth(sequence, config);
  const hil::ConsoleVerdicts verdicts(truth);
  if (args.has("--console-verdicts")) verdicts.attach(config);
  const hil::RunResult result = hil::run_hil(config, *dut);
  jsonl.commit();
  hil::write_report(report, config, result, truth);
  return summarise(result, report);
}

}  // namespace gabarit::cli
