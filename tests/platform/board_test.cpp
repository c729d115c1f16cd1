// The board application's pure pieces: luma extraction from captured frames
// (sizes from the driver are untrusted) and dropped-frame counting.
#include <gtest/gtest.h>

#include <vector>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>

#include "frame_counter.hpp"
#include "luma.hpp"
#include "udp_sender.hpp"

namespace gabarit::board {
namespace {

TEST(Luma, GreyAndNv12AreViewedInPlaceWithTheDriversStride) {
  // 5x3 frame, 8 bytes per line: the padding must not be read as pixels.
  std::vector<std::uint8_t> grey(8 * 3);
  for (std::size_t i = 0; i < grey.size(); ++i) grey[i] = static_cast<std::uint8_t>(i);
  ImageView view;
  ASSERT_EQ(luma_view({kFourccGrey, 5, 3, 8}, grey.data(), grey.size(), {}, view), LumaStatus::kOk);
  EXPECT_EQ(view.pixels, grey.data());
  EXPECT_EQ(view.stride, 8u);
  EXPECT_EQ(view.at(4, 2), 20);
  std::vector<std::uint8_t> nv12(8 * 3 + 8 * 2);  // Y rows, then CbCr at half height (rounded up)
  ASSERT_EQ(luma_view({kFourccNv12, 5, 3, 8}, nv12.data(), nv12.size(), {}, view), LumaStatus::kOk);
  EXPECT_EQ(view.pixels, nv12.data());
  EXPECT_EQ(luma_view({kFourccNv12, 5, 3, 8}, nv12.data(), nv12.size() - 1, {}, view), LumaStatus::kShortFrame);
}

TEST(Luma, YuyvKeepsEveryEvenByte) {
  const std::uint32_t w = 3, h = 2, stride = 8;  // 6 bytes of pixels + 2 of padding per row
  std::vector<std::uint8_t> yuyv(stride * h, 0xEE);
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      yuyv[y * stride + 2 * x] = static_cast<std::uint8_t>(10 * y + x);  // Y
      yuyv[y * stride + 2 * x + 1] = 0x80;                               // U or V
    }
  std::vector<std::uint8_t> scratch(luma_scratch_bytes({kFourccYuyv, w, h, stride}));
  ASSERT_EQ(scratch.size(), 6u);
  ImageView view;
  ASSERT_EQ(luma_view({kFourccYuyv, w, h, stride}, yuyv.data(), yuyv.size(), scratch, view), LumaStatus::kOk);
  EXPECT_EQ(view.stride, w);
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) EXPECT_EQ(view.at(x, y), 10 * y + x);
  std::vector<std::uint8_t> small(5);
  EXPECT_EQ(luma_view({kFourccYuyv, w, h, stride}, yuyv.data(), yuyv.size(), small, view), LumaStatus::kScratchTooSmall);
}

TEST(Luma, BadLayoutsAndFormatsAreRefused) {
  std::vector<std::uint8_t> data(64);
  ImageView view;
  EXPECT_EQ(luma_view({fourcc('M', 'J', 'P', 'G'), 4, 4, 4}, data.data(), data.size(), {}, view), LumaStatus::kUnsupportedFormat);
  EXPECT_EQ(luma_view({kFourccGrey, 4, 4, 3}, data.data(), data.size(), {}, view), LumaStatus::kBadLayout);
  EXPECT_EQ(luma_view({kFourccYuyv, 4, 4, 6}, data.data(), data.size(), data, view), LumaStatus::kBadLayout);
  EXPECT_EQ(luma_view({kFourccGrey, 0, 4, 4}, data.data(), data.size(), {}, view), LumaStatus::kBadLayout);
  EXPECT_EQ(luma_view({kFourccGrey, 8, 9, 8}, data.data(), data.size(), {}, view), LumaStatus::kShortFrame);
  EXPECT_EQ(luma_view({kFourccGrey, 8, 8, 8}, nullptr, 64, {}, view), LumaStatus::kShortFrame);
  EXPECT_STREQ(fourcc_text(kFourccYuyv).text, "YUYV");
}

TEST(FrameCounter, GapsInSequenceNumbersAreDroppedFrames) {
  FrameCounter c;
  EXPECT_EQ(c.delivered(7), 0u);  // the first frame seen: nothing known before it
  EXPECT_EQ(c.delivered(8), 0u);
  EXPECT_EQ(c.delivered(11), 2u);
  EXPECT_EQ(c.delivered(12), 0u);
  EXPECT_EQ(c.dropped_count(), 2u);
  EXPECT_EQ(c.delivered_count(), 4u);
  c.restart();  // the device was reopened: its count starts again
  EXPECT_EQ(c.delivered(0), 0u);
  EXPECT_EQ(c.delivered(1), 0u);
  EXPECT_EQ(c.delivered(0), 0u);  // backwards without a restart: a new run, not 4 billion drops
  EXPECT_EQ(c.dropped_count(), 2u);
}

TEST(UdpSender, SendsEachLineAsOneDatagram) {
  const int rx = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(rx, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(rx, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  socklen_t len = sizeof addr;
  ASSERT_EQ(::getsockname(rx, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  UdpSender udp;
  ASSERT_TRUE(udp.open("127.0.0.1:" + std::to_string(ntohs(addr.sin_port)))) << udp.error();
  udp.send("0,1.000,2.000,0.000,0,10,1.000000,tracking,7,123");
  udp.send("1,2.000,3.000,0.000,0,11,1.000000,tracking,8,456");
  for (const char* want : {"0,1.000,2.000,0.000,0,10,1.000000,tracking,7,123", "1,2.000,3.000,0.000,0,11,1.000000,tracking,8,456"}) {
    pollfd p{rx, POLLIN, 0};
    ASSERT_EQ(::poll(&p, 1, 2000), 1);
    char buffer[256];
    const ssize_t n = ::recv(rx, buffer, sizeof buffer, 0);
    ASSERT_GT(n, 0);
    EXPECT_EQ(std::string(buffer, static_cast<std::size_t>(n)), want);
  }
  EXPECT_EQ(udp.failed(), 0u);
  ::close(rx);
}

TEST(UdpSender, BadDestinationsAreRefusedWithAReason) {
  for (const char* bad : {"localhost", ":9000", "host:", "256.1.1.1.1:x"}) {
    UdpSender udp;
    EXPECT_FALSE(udp.open(bad)) << bad;
    EXPECT_NE(udp.error().find("--udp"), std::string::npos) << bad;
  }
}

}  // namespace
}  // namespace gabarit::board
