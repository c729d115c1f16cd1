#include "gabarit/hil/report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "gabarit/app/files.hpp"
#include "gabarit/app/pose_row.hpp"
#include "gabarit/app/svg_plot.hpp"
#include "gabarit/tracker.hpp"

namespace gabarit::hil {
namespace {

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      out += b;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string xml(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string num(double v, int digits = 3) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

std::string pose_columns(const FrameRecord& r) {
  if (!r.pose) return std::to_string(r.frame) + ",,,,,,,";
  app::TrackRow row;
  row.frame = r.frame;
  row.step.pose = r.pose->pose;
  row.step.best.votes = r.pose->best_votes;
  row.step.score = r.pose->score;
  row.step.state = static_cast<TrackState>(r.pose->state);
  return app::pose_csv_row(row);
}

const char* reference_text(int reference) { return reference == 1 ? "match" : reference == 0 ? "MISMATCH" : ""; }

double error_px(const FrameRecord& r, const std::map<std::uint32_t, app::PoseSample>& truth) {
  const auto it = truth.find(r.frame);
  if (!r.pose || it == truth.end() || !it->second.visible) return -1;
  return std::hypot(r.pose->pose.x - it->second.x, r.pose->pose.y - it->second.y);
}

struct Figures {
  LatencySummary latency, dut, cycles;
  LatencySummary camera, track, strobe;  // a camera DUT's stages
  double overhead_bytes = 0, codec_us = 0;
  std::map<Fate, std::size_t> fates;
  std::size_t sent = 0, poses = 0, matching = 0;
  // The reference's work per matching frame, by phase (frame_ledger.hpp).
  std::size_t ledgers = 0;
  double work[kFramePhaseCount] = {};
};

Figures figures(const RunResult& result) {
  Figures f;
  std::vector<double> latency, dut, cycles, camera, track, strobe;
  double overhead = 0;
  std::size_t clean = 0;
  for (const FrameRecord& r : result.frames) {
    // The overhead of a frame sent once, unfaulted, and answered with a pose.
    if (r.pose && r.fault < 0) overhead += static_cast<double>(r.wire_bytes) - r.pixel_bytes, ++clean;
    if (r.fate != Fate::kPending || r.sent_us >= 0) ++f.fates[r.fate];
    if (r.sent_us >= 0) ++f.sent;
    if (!r.pose) continue;
    ++f.poses;
    f.matching += r.reference == 1;
    if (r.reference == 1 && r.reference_ledger) {
      ++f.ledgers;
      for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) f.work[p] += static_cast<double>(r.reference_ledger->work[p]);
    }
    latency.push_back(r.latency_us);
    if (r.camera_us >= 0) camera.push_back(r.camera_us);
    if (r.track_us >= 0) track.push_back(r.track_us);
    if (r.strobe_us >= 0) strobe.push_back(r.strobe_us);
    if (r.dut_us >= 0) dut.push_back(r.dut_us);
    if (r.pose->cycles != 0) cycles.push_back(static_cast<double>(r.pose->cycles));
  }
  f.latency = summarise(latency);
  f.dut = summarise(dut);
  f.cycles = summarise(cycles);
  f.camera = summarise(camera);
  f.track = summarise(track);
  f.strobe = summarise(strobe);
  if (clean > 0) f.overhead_bytes = overhead / static_cast<double>(clean);
  if (f.sent > 0) f.codec_us = result.host_codec_seconds * 1e6 / static_cast<double>(f.sent);
  if (f.ledgers > 0)
    for (double& w : f.work) w /= static_cast<double>(f.ledgers);
  return f;
}

// The reference's work per matching frame by phase (null: no reference).
std::string work_json(const Figures& f) {
  if (f.ledgers == 0) return "null";
  std::ostringstream s;
  s << "{\"frames\": " << f.ledgers;
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) s << ", \"" << frame_phase_name(static_cast<FramePhase>(p)) << "\": " << num(f.work[p], 1);
  s << "}";
  return s.str();
}

std::string latency_json(const LatencySummary& s) {
  return "{\"samples\": " + std::to_string(s.samples) + ", \"p50\": " + num(s.p50) + ", \"p99\": " + num(s.p99) +
         ", \"max\": " + num(s.max) + ", \"mean\": " + num(s.mean) + "}";
}

// A fault timeline: one row per fault kind, a mark at each faulted frame,
// green when detected and recovered from, red otherwise.
std::string fault_timeline(const RunResult& result) {
  const double width = 720, left = 90, right = 20, row = 22, top = 30;
  const double n = std::max<double>(1, result.frames_total);
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << top + row * 6 + 30
    << "\" font-family=\"sans-serif\" font-size=\"11\">\n<text x=\"" << width / 2
    << "\" y=\"16\" text-anchor=\"middle\" font-size=\"13\">Injected faults by frame (green: detected and recovered)</text>\n";
  for (int k = 0; k < 6; ++k) {
    const double y = top + row * k + row / 2;
    s << "<text x=\"" << left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << fault_name(kAllFaultKinds[k]) << "</text>\n"
      << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << width - right << "\" y2=\"" << y << "\" stroke=\"#ddd\"/>\n";
  }
  for (const InjectedFault& f : result.faults) {
    const double x = left + (width - left - right) * (f.frame + 0.5) / n;
    const double y = top + row * static_cast<int>(f.kind) + row / 2;
    s << "<rect x=\"" << x - 1.5 << "\" y=\"" << y - 7 << "\" width=\"3\" height=\"14\" fill=\""
      << (f.detected && f.recovered ? "#2a2" : "#d22") << "\"><title>frame " << f.frame << ": " << xml(f.evidence)
      << "</title></rect>\n";
  }
  const double axis = top + row * 6 + 14;
  s << "<text x=\"" << left << "\" y=\"" << axis << "\">0</text><text x=\"" << width - right << "\" y=\"" << axis
    << "\" text-anchor=\"end\">" << result.frames_total << " frames</text>\n</svg>\n";
  return s.str();
}

}  // namespace

std::vector<Check> run_checks(const RunResult& result) {
  std::vector<Check> checks;
  const Figures f = figures(result);
  checks.push_back({"handshake", result.caps.refusal == link::Refusal::kNone && result.caps.frame_slots > 0,
                    result.caps.frame_slots > 0 ? std::string("CAPS from ") + result.caps.kind + " on " + result.caps.board
                                                : "no CAPS: " + result.error});
  checks.push_back({"run_complete", result.error.empty(), result.error.empty() ? "every frame was sent" : result.error});
  checks.push_back({"frames_accounted", result.unaccounted == 0 && result.error.empty(),
                    std::to_string(result.unaccounted) + " of " + std::to_string(f.sent) + " frames sent have no fate"});
  checks.push_back({"poses_in_order", result.out_of_order == 0,
                    std::to_string(result.out_of_order) + " poses came for a frame older than one already posed"});
  checks.push_back({"one_answer_per_frame", result.double_answers == 0 && result.unknown_answers == 0,
                    std::to_string(result.double_answers) + " second answers, " + std::to_string(result.unknown_answers) +
                        " answers for frames never sent"});
  std::string first_mismatch;
  std::size_t crc_bad = 0;
  for (const FrameRecord& r : result.frames) {
    if (r.reference == 0 && first_mismatch.empty()) first_mismatch = "; first at frame " + std::to_string(r.frame) + ": " + r.mismatch;
    crc_bad += r.pose && !r.frame_crc_ok;
  }
  checks.push_back({"poses_match_reference", f.poses > 0 && f.matching == f.poses,
                    std::to_string(f.matching) + " of " + std::to_string(f.poses) + " poses bit-identical to the host's" + first_mismatch});
  checks.push_back({"frames_intact", crc_bad == 0, std::to_string(crc_bad) + " poses for pixels other than those sent (CRC-32C)"});
  checks.push_back({"messages_from_dut_valid", result.bad_messages_in == 0,
                    std::to_string(result.bad_messages_in) + " messages from the DUT failed their checks"});
  for (std::size_t i = 0; i < result.faults.size(); ++i) {
    const InjectedFault& x = result.faults[i];
    checks.push_back({"fault." + std::to_string(i) + "." + fault_name(x.kind) + ".frame" + std::to_string(x.frame),
                      x.detected && x.recovered,
                      std::string(x.detected ? "detected" : "NOT detected") + (x.recovered ? ", recovered" : ", NOT recovered") +
                          ": " + x.detail + "; " + x.evidence});
  }
  return checks;
}

std::string frame_json(const FrameRecord& r) {
  std::ostringstream s;
  s << "{\"frame\": " << r.frame << ", \"fate\": " << json_string(fate_name(r.fate)) << ", \"reason\": " << json_string(r.reason)
    << ", \"run\": " << r.run;
  if (r.pose) {
    s << ", \"x\": " << num(r.pose->pose.x, 6) << ", \"y\": " << num(r.pose->pose.y, 6) << ", \"theta_deg\": " << num(r.pose->pose.theta_deg, 6)
      << ", \"depth\": " << r.pose->pose.depth << ", \"votes\": " << r.pose->best_votes << ", \"score\": " << num(r.pose->score, 6)
      << ", \"status\": " << json_string(track_state_name(static_cast<TrackState>(r.pose->state)))
      << ", \"reference\": " << json_string(reference_text(r.reference)) << ", \"latency_us\": " << num(r.latency_us, 1)
      << ", \"dut_us\": " << num(r.dut_us, 1) << ", \"cycles\": " << r.pose->cycles;
    if (!r.mismatch.empty()) s << ", \"mismatch\": " << json_string(r.mismatch);
  }
  if (r.fault >= 0) s << ", \"fault\": " << r.fault;
  s << "}";
  return s.str();
}

namespace {

// frames.csv, poses.csv, faults.csv and (a soak) soak.csv.
void write_csvs(const std::filesystem::path& d, const RunConfig& config, const RunResult& result) {
  std::string frames = std::string(app::kPoseCsvHeader) +
                       ",fate,reason,reference,latency_us,dut_us,cycles,wire_bytes,fault,camera_us,track_us,strobe_us";
  for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) {
    frames += ',';
    frames += frame_phase_name(static_cast<FramePhase>(p));
    frames += "_work";
  }
  frames += "\n";
  std::string poses = std::string(app::kPoseCsvHeader) + "\n";
  for (const FrameRecord& r : result.frames) {
    if (r.sent_us < 0 && r.fate == Fate::kPending) continue;  // never reached (a run that stopped early)
    std::string reason = r.reason;
    std::replace(reason.begin(), reason.end(), ',', ';');
    frames += pose_columns(r) + "," + fate_name(r.fate) + "," + reason + "," + reference_text(r.reference) + "," +
              (r.pose ? num(r.latency_us, 1) : "") + "," + (r.pose && r.dut_us >= 0 ? num(r.dut_us, 1) : "") + "," +
              (r.pose ? std::to_string(r.pose->cycles) : "") + "," + std::to_string(r.wire_bytes) + "," +
              (r.fault >= 0 ? fault_name(result.faults[static_cast<std::size_t>(r.fault)].kind) : "") + "," +
              (r.camera_us >= 0 ? num(r.camera_us, 0) : "") + "," + (r.track_us >= 0 ? num(r.track_us, 0) : "") + "," +
              (r.strobe_us >= 0 ? num(r.strobe_us, 0) : "");
    for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) {
      frames += ',';
      if (r.reference_ledger) frames += std::to_string(r.reference_ledger->work[p]);
    }
    frames += "\n";
    if (r.pose) poses += pose_columns(r) + "\n";
  }
  app::write_file((d / "frames.csv").string(), frames);
  app::write_file((d / "poses.csv").string(), poses);
  app::write_file((d / "faults.csv").string(), fault_file_text(config.faults));
  if (!result.soak.empty()) {
    std::string soak = "frames,seconds,host_rss_kib,dut_rss_kib,latency_p50_us,latency_p99_us\n";
    for (const SoakSample& x : result.soak)
      soak += std::to_string(x.frames) + "," + num(x.seconds, 1) + "," + std::to_string(x.host_rss_kib) + "," +
              std::to_string(x.dut_rss_kib) + "," + num(x.latency_p50_us, 1) + "," + num(x.latency_p99_us, 1) + "\n";
    app::write_file((d / "soak.csv").string(), soak);
  }

}

// Accuracy against ground truth over the frames the run had; `accuracy` its
// JSON ("null" without ground truth).
app::Accuracy accuracy_against(const RunResult& result, const std::vector<app::PoseSample>& truth, std::string& accuracy) {
  accuracy = "null";
  app::Accuracy a;
  if (!truth.empty()) {
    std::vector<app::PoseSample> got, want;
    for (const FrameRecord& r : result.frames) {
      if (!r.pose) continue;
      got.push_back({r.frame, r.pose->pose.x, r.pose->pose.y, r.pose->pose.theta_deg, r.pose->pose.depth, true});
    }
    for (const app::PoseSample& t : truth)
      if (t.frame < result.frames_total) want.push_back(t);
    a = app::evaluate(got, want);
    accuracy = app::accuracy_json(a);
    while (!accuracy.empty() && (accuracy.back() == '\n' || accuracy.back() == ' ')) accuracy.pop_back();
  }

  return a;
}

// summary.json.
std::string summary_json(const RunConfig& config, const RunResult& result, const Figures& f, const std::vector<Check>& checks,
                         std::size_t failed, const std::string& accuracy) {
  const link::Caps& c = result.caps;
  std::ostringstream s;
  s << "{\n  \"dut\": {\"kind\": " << json_string(c.kind) << ", \"board\": " << json_string(c.board)
    << ", \"firmware\": " << json_string(c.firmware) << ", \"device_id\": \"" << std::hex << c.device_id << std::dec
    << "\", \"table_crc32\": " << c.table_crc << ", \"table_bytes\": " << c.table_bytes << ", \"clock_hz\": " << c.clock_hz
    << ", \"frame_slots\": " << c.frame_slots << ", \"max_payload\": " << c.max_payload << ", \"mode\": " << c.mode
    << ", \"driver\": " << json_string(result.dut_description) << "},\n"
    << "  \"sequence\": " << json_string(config.sequence_dir) << ",\n  \"table\": " << json_string(config.table_path) << ",\n"
    << "  \"frames\": " << result.frames_total << ", \"frames_sent\": " << f.sent << ", \"poses\": " << f.poses
    << ", \"unaccounted\": " << result.unaccounted << ", \"out_of_order\": " << result.out_of_order
    << ", \"double_answers\": " << result.double_answers << ",\n  \"fates\": {";
  bool first = true;
  for (const auto& [fate, n] : f.fates) {
    s << (first ? "" : ", ") << json_string(fate_name(fate)) << ": " << n;
    first = false;
  }
  s << "},\n  \"poses_matching_reference\": " << f.matching << ",\n  \"restarts\": {\"planned\": " << result.restarts_planned
    << ", \"hung\": " << result.restarts_hung << ", \"crashed\": " << result.restarts_crashed
    << ", \"by_the_rig\": " << result.restarts_reported << "},\n"
    << "  \"latency_us\": " << latency_json(f.latency) << ",\n  \"dut_time_us\": " << latency_json(f.dut)
    << ",\n  \"voter_cycles\": " << latency_json(f.cycles) << ",\n  \"work_per_frame\": " << work_json(f) << ",\n"
    << "  \"stages_us\": {\"camera\": " << latency_json(f.camera) << ", \"track\": " << latency_json(f.track)
    << ", \"strobe\": " << latency_json(f.strobe) << "},\n"
    << "  \"overhead_per_frame\": {\"bytes\": " << num(f.overhead_bytes, 1) << ", \"host_us\": " << num(f.codec_us, 2)
    << ", \"wire_bytes_total\": " << result.wire_bytes << ", \"pixel_bytes_total\": " << result.pixel_bytes_sent << "},\n"
    << "  \"faults\": [";
  for (std::size_t i = 0; i < result.faults.size(); ++i) {
    const InjectedFault& x = result.faults[i];
    s << (i ? ",\n    " : "\n    ") << "{\"frame\": " << x.frame << ", \"kind\": " << json_string(fault_name(x.kind))
      << ", \"detail\": " << json_string(x.detail) << ", \"detected\": " << (x.detected ? "true" : "false")
      << ", \"recovered\": " << (x.recovered ? "true" : "false") << ", \"evidence\": " << json_string(x.evidence);
    if (x.recovery_ms >= 0) s << ", \"recovery_ms\": " << num(x.recovery_ms, 1);
    s << "}";
  }
  s << (result.faults.empty() ? "" : "\n  ") << "],\n  \"dut_stats\": ";
  if (result.dut_stats) {
    const link::Stats& t = *result.dut_stats;
    s << "{\"messages_in\": " << t.messages_in << ", \"bad_crc\": " << t.bad_crc << ", \"bad_message\": " << t.bad_message
      << ", \"unknown_type\": " << t.unknown_type << ", \"framing_errors\": " << t.framing_errors
      << ", \"sequence_gaps\": " << t.sequence_gaps << ", \"stale\": " << t.stale << ", \"frames_taken\": " << t.frames_taken
      << ", \"frames_tracked\": " << t.frames_tracked << ", \"frames_dropped\": " << t.frames_dropped
      << ", \"frames_skipped\": " << t.frames_skipped << ", \"messages_out\": " << t.messages_out
      << ", \"resident_kib\": " << t.resident_kib << "}";
  } else {
    s << "null";
  }
  if (!result.soak.empty()) {
    const SoakSample& a0 = result.soak.front();
    const SoakSample& a1 = result.soak.back();
    s << ",\n  \"soak\": {\"samples\": " << result.soak.size() << ", \"host_rss_kib\": [" << a0.host_rss_kib << ", "
      << a1.host_rss_kib << "], \"dut_rss_kib\": [" << a0.dut_rss_kib << ", " << a1.dut_rss_kib
      << "], \"latency_p50_us\": [" << num(a0.latency_p50_us, 1) << ", " << num(a1.latency_p50_us, 1) << "]}";
  }
  s << ",\n  \"accuracy\": " << accuracy << ",\n  \"checks_failed\": " << failed << ",\n  \"checks\": [";
  for (std::size_t i = 0; i < checks.size(); ++i)
    s << (i ? ",\n    " : "\n    ") << "{\"name\": " << json_string(checks[i].name) << ", \"passed\": "
      << (checks[i].passed ? "true" : "false") << ", \"message\": " << json_string(checks[i].message) << "}";
  s << "\n  ],\n  \"error\": " << json_string(result.error) << ",\n  \"seconds\": " << num(result.seconds, 2) << "\n}\n";

  return s.str();
}

// junit.xml: one testsuite, a testcase per check (faults included), the
// figures as properties.
std::string junit_xml(const RunResult& result, const Figures& f, const std::vector<Check>& checks, std::size_t failed,
                      const std::vector<app::PoseSample>& truth, const app::Accuracy& a) {
  const link::Caps& c = result.caps;
  std::ostringstream j;
  const std::string suite = std::string("hil.") + (c.kind[0] ? c.kind : "dut");
  j << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n<testsuite name=\"" << xml(suite) << "\" tests=\"" << checks.size()
    << "\" failures=\"" << failed << "\" errors=\"0\" time=\"" << num(result.seconds, 3) << "\">\n<properties>\n";
  const auto property = [&](const std::string& name, const std::string& value) {
    j << "  <property name=\"" << xml(name) << "\" value=\"" << xml(value) << "\"/>\n";
  };
  property("dut.kind", c.kind);
  property("dut.board", c.board);
  property("dut.firmware", c.firmware);
  property("dut.device_id", std::to_string(c.device_id));
  property("frames", std::to_string(result.frames_total));
  property("poses", std::to_string(f.poses));
  property("latency_us.p50", num(f.latency.p50));
  property("latency_us.p99", num(f.latency.p99));
  property("latency_us.max", num(f.latency.max));
  property("dut_time_us.p50", num(f.dut.p50));
  property("dut_time_us.p99", num(f.dut.p99));
  property("dut_time_us.max", num(f.dut.max));
  if (f.cycles.samples) {
    property("voter_cycles.p50", num(f.cycles.p50, 0));
    property("voter_cycles.max", num(f.cycles.max, 0));
  }
  property("overhead.bytes_per_frame", num(f.overhead_bytes, 1));
  property("overhead.host_us_per_frame", num(f.codec_us, 2));
  if (!truth.empty()) property("accuracy.within_1px", std::to_string(a.within_1px) + "/" + std::to_string(a.frames));
  j << "</properties>\n";
  for (const Check& k : checks) {
    j << "<testcase classname=\"" << xml(suite) << "\" name=\"" << xml(k.name) << "\" time=\"0\">";
    if (!k.passed) j << "<failure message=\"" << xml(k.message) << "\"/>";
    else j << "<system-out>" << xml(k.message) << "</system-out>";
    j << "</testcase>\n";
  }
  j << "</testsuite>\n</testsuites>\n";

  return j.str();
}

// error.svg, trajectory.svg, latency.svg, faults.svg: the names of those written.
std::vector<std::string> write_plots(const std::filesystem::path& d, const RunResult& result, const Figures& f,
                                     const std::vector<app::PoseSample>& truth) {
  std::map<std::uint32_t, app::PoseSample> truth_by_frame;
  for (const app::PoseSample& t : truth) truth_by_frame[t.frame] = t;
  std::vector<app::svg::Series> error_series(1), trajectory(2), histogram(1);
  error_series[0].label = "pose error (px)";
  trajectory[0].label = "truth";
  trajectory[1].label = "DUT";
  for (const FrameRecord& r : result.frames) {
    const double e = error_px(r, truth_by_frame);
    if (e >= 0) error_series[0].x.push_back(r.frame), error_series[0].y.push_back(e);
    if (r.pose) trajectory[1].x.push_back(r.pose->pose.x), trajectory[1].y.push_back(-r.pose->pose.y);
  }
  for (const app::PoseSample& t : truth)
    if (t.frame < result.frames_total) trajectory[0].x.push_back(t.x), trajectory[0].y.push_back(-t.y);
  std::vector<std::string> plots;
  if (!error_series[0].x.empty()) {
    app::svg::write((d / "error.svg").string(), app::svg::lines("Pose error against ground truth", "frame", "error (px)", error_series, false, false));
    plots.push_back("error.svg");
  }
  if (!trajectory[1].x.empty()) {
    if (trajectory[0].x.empty()) trajectory.erase(trajectory.begin());
    app::svg::write((d / "trajectory.svg").string(), app::svg::lines("Trajectory (y up)", "x (px)", "-y (px)", trajectory, false, false));
    plots.push_back("trajectory.svg");
  }
  std::vector<double> latencies;
  for (const FrameRecord& r : result.frames)
    if (r.pose) latencies.push_back(r.latency_us);
  if (!latencies.empty()) {
    const double top = *std::max_element(latencies.begin(), latencies.end());
    const int bins = 40;
    std::vector<double> counts(bins, 0);
    for (double v : latencies) ++counts[static_cast<std::size_t>(std::min(bins - 1, static_cast<int>(v / (top + 1e-9) * bins)))];
    histogram[0].label = "frames (p50 " + num(f.latency.p50, 0) + ", p99 " + num(f.latency.p99, 0) + ", max " + num(f.latency.max, 0) + " us)";
    for (int b = 0; b < bins; ++b) histogram[0].x.push_back((b + 0.5) * top / bins), histogram[0].y.push_back(counts[static_cast<std::size_t>(b)]);
    app::svg::write((d / "latency.svg").string(), app::svg::lines("Latency, frame sent to pose received", "latency (us)", "frames", histogram, false, false));
    plots.push_back("latency.svg");
  }
  app::svg::write((d / "faults.svg").string(), fault_timeline(result));
  plots.push_back("faults.svg");

  return plots;
}

// report.md.
std::string markdown(const RunConfig& config, const RunResult& result, const Figures& f, const std::vector<Check>& checks,
                     std::size_t failed, const std::vector<app::PoseSample>& truth, const app::Accuracy& a,
                     const std::vector<std::string>& plots) {
  const link::Caps& c = result.caps;
  std::ostringstream m;
  m << "# HIL run: " << (c.kind[0] ? c.kind : "(no DUT)") << "\n\n"
    << "| | |\n|---|---|\n| DUT | " << c.kind << " on " << c.board << ", " << c.firmware << ", device id " << std::hex << c.device_id
    << std::dec << " |\n| driver | `" << result.dut_description << "` |\n| sequence | `" << config.sequence_dir << "` |\n| table | `"
    << config.table_path << "` (CRC-32 " << c.table_crc << ", " << c.table_bytes << " bytes) |\n| frames | " << result.frames_total
    << " (" << f.sent << " sent, " << f.poses << " poses) |\n| checks | " << checks.size() - failed << " passed, " << failed
    << " failed |\n\n## Fates\n\n| fate | frames |\n|---|---|\n";
  for (const auto& [fate, n] : f.fates) m << "| " << fate_name(fate) << " | " << n << " |\n";
  m << "\n## Timing\n\n| | p50 | p99 | max |\n|---|---|---|---|\n| latency, sent to pose (us) | " << num(f.latency.p50, 1) << " | "
    << num(f.latency.p99, 1) << " | " << num(f.latency.max, 1) << " |\n| DUT time, received to done (us, its clock at "
    << c.clock_hz << " Hz) | " << num(f.dut.p50, 1) << " | " << num(f.dut.p99, 1) << " | " << num(f.dut.max, 1) << " |\n";
 if (f.camera.samples)
    m << "| camera: shown to captured (us) | " << num(f.camera.p50, 0) << " | " << num(f.camera.p99, 0) << " | " << num(f.camera.max, 0)
      << " |\n| tracking: captured to pose (us) | " << num(f.track.p50, 0) << " | " << num(f.track.p99, 0) << " | "
      << num(f.track.max, 0) << " |\n";
  if (f.strobe.samples)
    m << "| strobe: pose to the line's edge (us) | " << num(f.strobe.p50, 0) << " | " << num(f.strobe.p99, 0) << " | "
      << num(f.strobe.max, 0) << " |\n";
  if (f.cycles.samples)
    m << "| voter cycles per frame | " << num(f.cycles.p50, 0) << " | " << num(f.cycles.p99, 0) << " | " << num(f.cycles.max, 0) << " |\n";
  if (f.ledgers > 0) {
    m << "\nWork per frame by phase (frame_ledger.hpp), counted by the host's reference over the " << f.ledgers
      << " matching frames (the DUT's own: work is the same on every target):";
    for (std::uint32_t p = 0; p < kFramePhaseCount; ++p)
      m << (p ? ", " : " ") << frame_phase_name(static_cast<FramePhase>(p)) << " " << num(f.work[p], 0);
    m << ".\n";
  }
  m << "\nProtocol overhead per frame: " << num(f.overhead_bytes, 1)
    << " bytes on the wire beyond the pixels (frames sent once and posed, their POSE included), " << num(f.codec_us, 2)
    << " us of host time (headers, CRC-32C, COBS, per frame sent).\n\n";
  if (!truth.empty())
    m << "Accuracy against ground truth: " << a.within_1px << " of " << a.frames << " posed frames within 1 px, mean error "
      << num(a.mean_error_px, 3) << " px, " << a.missing << " visible frames without a pose.\n\n";
  m << "## Checks\n\n| check | result | detail |\n|---|---|---|\n";
  for (const Check& k : checks) m << "| " << k.name << " | " << (k.passed ? "pass" : "**FAIL**") << " | " << k.message << " |\n";
  m << "\n## Plots\n\n";
  for (const std::string& p : plots) m << "![" << p << "](" << p << ")\n\n";
  return m.str();
}

}  // namespace

void write_report(const std::string& dir, const RunConfig& config, const RunResult& result, const std::vector<app::PoseSample>& truth) {
  std::filesystem::create_directories(dir);
  const std::filesystem::path d(dir);
  const Figures f = figures(result);
  const std::vector<Check> checks = run_checks(result);
  std::size_t failed = 0;
  for (const Check& k : checks) failed += !k.passed;
  write_csvs(d, config, result);
  std::string accuracy;
  const app::Accuracy a = accuracy_against(result, truth, accuracy);
  app::write_file((d / "summary.json").string(), summary_json(config, result, f, checks, failed, accuracy));
  app::write_file((d / "junit.xml").string(), junit_xml(result, f, checks, failed, truth, a));
  const std::vector<std::string> plots = write_plots(d, result, f, truth);
  app::write_file((d / "report.md").string(), markdown(config, result, f, checks, failed, truth, a, plots));
}

}  // namespace gabarit::hil
