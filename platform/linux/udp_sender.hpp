// Pose lines as UDP datagrams (one line per datagram) to HOST:PORT. Sending
// never blocks the tracking loop: a full socket buffer or an unreachable
// peer drops the datagram and counts it.
#pragma once

#include <cstdint>
#include <string>

namespace gabarit::board {

class UdpSender {
 public:
  UdpSender() = default;
  ~UdpSender();
  UdpSender(const UdpSender&) = delete;
  UdpSender& operator=(const UdpSender&) = delete;

  // "HOST:PORT" or "[IPv6]:PORT". False with error() on a bad address.
  [[nodiscard]] bool open(const std::string& destination);
  bool is_open() const { return fd_ >= 0; }
  void send(const std::string& line);
  std::uint64_t failed() const { return failed_; }
  const std::string& error() const { return error_; }

 private:
  int fd_ = -1;
  std::uint64_t failed_ = 0;
  std::string error_;
};

}  // namespace gabarit::board
