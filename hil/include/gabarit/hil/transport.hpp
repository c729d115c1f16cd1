// The harness's side of a link: send a message, receive one with a deadline
// that always fires. Byte streams (sockets, pipes, a QEMU chardev) carry
// messages COBS-framed; message transports (UDP, the in-process loopback)
// one per datagram. Faults are injected above this interface (faults.hpp),
// so every transport is tested the same way.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "gabarit/link/cobs.hpp"
#include "gabarit/link/protocol.hpp"

namespace gabarit::hil {

using Clock = std::chrono::steady_clock;

class Transport {
 public:
  virtual ~Transport() = default;
  // Sends one encoded message (header, payload, CRC). `mangle`, if given,
  // may alter the bytes as they go on the wire (after framing): the fault
  // scheduler's bit flips. Throws app::Error when the link is gone or the
  // send cannot complete by `deadline`.
  virtual void send(std::span<const std::byte> message, Clock::time_point deadline) = 0;
  // The next message, de-framed (not yet checked: decode_message does), or
  // nothing by `deadline`. Throws app::Error when the link is gone.
  virtual std::optional<std::vector<std::byte>> receive(Clock::time_point deadline) = 0;
  // Bytes this side put on the wire (framing included), for the overhead figure.
  std::uint64_t bytes_sent() const { return bytes_sent_; }
  // Framing errors seen by this side's decoder (streams).
  virtual std::uint32_t framing_errors() const { return 0; }
  // Bytes `message` takes on the wire (with its framing).
  virtual std::size_t wire_size(std::span<const std::byte> message) const { return message.size(); }
  // Host time spent framing and de-framing (COBS), seconds.
  double framing_seconds() const { return framing_seconds_; }

  // The fault scheduler's hook: flip these bit positions of the next send's
  // wire bytes (positions beyond its length wrap).
  void flip_bits_on_next_send(std::vector<std::uint64_t> bits) { flips_ = std::move(bits); }

 protected:
  void apply_flips(std::span<std::byte> wire);
  std::uint64_t bytes_sent_ = 0;
  double framing_seconds_ = 0;

 private:
  std::vector<std::uint64_t> flips_;
};

// A byte-stream file descriptor (a socket, a pipe pair) with COBS framing.
// Owns the descriptors.
class StreamTransport : public Transport {
 public:
  StreamTransport(int read_fd, int write_fd, std::string name);
  ~StreamTransport() override;
  void send(std::span<const std::byte> message, Clock::time_point deadline) override;
  std::optional<std::vector<std::byte>> receive(Clock::time_point deadline) override;
  std::uint32_t framing_errors() const override { return decoder_.overlong() + decoder_.malformed(); }
  std::size_t wire_size(std::span<const std::byte> message) const override;

 private:
  int read_fd_, write_fd_;
  std::string name_;
  std::vector<std::byte> buffer_;
  link::CobsStreamDecoder decoder_;
  std::vector<std::byte> pending_;  // bytes read past the last message
  std::size_t pending_at_ = 0;
};

// UDP datagrams to a peer, one message each (127.0.0.1 or any address).
class UdpTransport : public Transport {
 public:
  // Binds `local_port` (0: any) and sends to host:peer_port.
  UdpTransport(const std::string& host, std::uint16_t peer_port, std::uint16_t local_port = 0);
  ~UdpTransport() override;
  std::uint16_t local_port() const { return local_port_; }
  void set_peer(std::uint16_t peer_port) { peer_port_ = peer_port; }
  void send(std::span<const std::byte> message, Clock::time_point deadline) override;
  std::optional<std::vector<std::byte>> receive(Clock::time_point deadline) override;

 private:
  int fd_;
  std::string host_;
  std::uint16_t peer_port_, local_port_ = 0;
};

// Two in-memory ends of a message link, for a DUT on a thread of this
// process. Thread-safe; close() wakes a waiting receiver, which then throws.
class Loopback {
 public:
  class End : public Transport {
   public:
    void send(std::span<const std::byte> message, Clock::time_point deadline) override;
    std::optional<std::vector<std::byte>> receive(Clock::time_point deadline) override;

   private:
    friend class Loopback;
    End(std::shared_ptr<struct LoopbackState> state, int side) : state_(std::move(state)), side_(side) {}
    std::shared_ptr<struct LoopbackState> state_;
    int side_;
  };
  Loopback();
  std::unique_ptr<End> host_end();
  std::unique_ptr<End> device_end();
  void close();

 private:
  std::shared_ptr<struct LoopbackState> state_;
};

struct LoopbackState {
  std::mutex mutex;
  std::condition_variable ready;
  std::deque<std::vector<std::byte>> queue[2];  // [0]: to the device, [1]: to the host
  bool closed = false;
};

}  // namespace gabarit::hil
