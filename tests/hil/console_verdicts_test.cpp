// The harness's verdict lines for a DUT's console (console_verdicts.hpp),
// which a board farm's monitors turn into test cases (docs/hil-farm.md).
#include "gabarit/hil/console_verdicts.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "gabarit/link/protocol.hpp"

namespace gabarit::hil {
namespace {

FrameRecord posed(std::uint32_t frame, float x, float y, int reference) {
  FrameRecord r;
  r.frame = frame;
  r.fate = Fate::kPose;
  link::PoseReport pose;
  pose.pose.x = x;
  pose.pose.y = y;
  r.pose = pose;
  r.reference = reference;
  return r;
}

TEST(ConsoleVerdicts, AFramePassesOnlyBitIdenticalAndItsErrorIsAgainstTheGroundTruth) {
  const ConsoleVerdicts verdicts({{7, 10.0, 20.0, 0.0, 0, true}, {8, 10.0, 20.0, 0.0, 0, false}});
  EXPECT_EQ(verdicts.frame_line(posed(7, 13.f, 24.f, 1)), "gabarit-hil case=frame-000007 result=pass measurement=5.000 units=px");
  EXPECT_EQ(verdicts.frame_line(posed(7, 10.f, 20.f, 0)), "gabarit-hil case=frame-000007 result=fail measurement=0.000 units=px");
  // No ground truth where the object is hidden, nor for a frame not in gt.csv.
  EXPECT_EQ(verdicts.frame_line(posed(8, 13.f, 24.f, 1)), "gabarit-hil case=frame-000008 result=pass measurement=0.000 units=none");
  EXPECT_EQ(verdicts.frame_line(posed(9, 13.f, 24.f, 1)), "gabarit-hil case=frame-000009 result=pass measurement=0.000 units=none");
  FrameRecord tampered = posed(7, 13.f, 24.f, 1);
  tampered.frame_crc_ok = false;  // a pose for other pixels than those sent
  EXPECT_NE(verdicts.frame_line(tampered).find(" result=fail "), std::string::npos);
  FrameRecord dropped;
  dropped.frame = 12;
  dropped.fate = Fate::kDroppedByDut;
  EXPECT_EQ(verdicts.frame_line(dropped), "gabarit-hil case=frame-000012 result=fail measurement=0.000 units=none");
  dropped.fault = 0;  // a fault was planned on it: its own check judges it
  EXPECT_EQ(verdicts.frame_line(dropped), "gabarit-hil case=frame-000012 result=skip measurement=0.000 units=none");
  for (const FrameRecord& r : {posed(4000000000u, 1e9f, -1e9f, 1), dropped})
    EXPECT_LT(verdicts.frame_line(r).size(), sizeof(link::Note::text));  // a NOTE holds every line
}

TEST(ConsoleVerdicts, TheClosingLinesAreTheChecksBetweenTheMonitorsMarkers) {
  RunResult result;
  result.caps.frame_slots = 1;
  result.frames.push_back(posed(0, 1.f, 1.f, 0));  // a mismatch: poses_match_reference fails
  result.frames[0].sent_us = 0;
  const std::vector<std::string> lines = ConsoleVerdicts({}).closing_lines(result);
  ASSERT_GE(lines.size(), 4u);
  EXPECT_EQ(lines.front(), kConsoleFramesEnd);
  EXPECT_EQ(lines[1], kConsoleChecksStart);
  EXPECT_EQ(lines[2], "gabarit-hil case=handshake result=pass");
  std::size_t failed = 0;
  for (const std::string& line : lines) failed += line.find("result=fail") != std::string::npos;
  EXPECT_EQ(failed, 1u);
  EXPECT_NE(std::find(lines.begin(), lines.end(), "gabarit-hil case=poses_match_reference result=fail"), lines.end());
  EXPECT_EQ(lines.back(), std::string(kConsoleRunEnd) + ", 1 of " + std::to_string(lines.size() - 3) + " checks failed");
}

}  // namespace
}  // namespace gabarit::hil
