#include "gabarit/hil/transport.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "gabarit/app/error.hpp"

namespace gabarit::hil {
namespace {

int millis_until(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  if (left <= 0) return 0;
  return left > 1000000 ? 1000000 : static_cast<int>(left) + 1;
}

void set_nonblocking(int fd) {
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags < 0 || ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0)
    throw app::Error(std::string("link: cannot make a descriptor non-blocking: ") + std::strerror(errno));
}

}  // namespace

void Transport::apply_flips(std::span<std::byte> wire) {
  if (wire.empty()) return;
  for (const std::uint64_t bit : flips_) {
    const std::uint64_t at = bit % (wire.size() * 8);
    wire[at / 8] ^= std::byte(1u << (at % 8));
  }
  flips_.clear();
}

StreamTransport::StreamTransport(int read_fd, int write_fd, std::string name)
    : read_fd_(read_fd), write_fd_(write_fd), name_(std::move(name)),
      buffer_(link::message_bytes(link::kMaxPayload)), decoder_(buffer_), pending_(65536) {
  set_nonblocking(read_fd_);
  if (write_fd_ != read_fd_) set_nonblocking(write_fd_);
  pending_.clear();
}

StreamTransport::~StreamTransport() {
  ::close(read_fd_);
  if (write_fd_ != read_fd_) ::close(write_fd_);
}

std::size_t StreamTransport::wire_size(std::span<const std::byte> message) const {
  std::vector<std::byte> wire(link::cobs_encoded_capacity(message.size()));
  std::size_t n = 0;
  return link::cobs_encode(message, wire, n) == Status::kOk ? n : wire.size();
}

void StreamTransport::send(std::span<const std::byte> message, Clock::time_point deadline) {
  const auto framing_start = Clock::now();
  std::vector<std::byte> wire(link::cobs_encoded_capacity(message.size()));
  std::size_t n = 0;
  if (link::cobs_encode(message, wire, n) != Status::kOk) throw app::Error(name_ + ": cannot frame a message");
  wire.resize(n);
  framing_seconds_ += std::chrono::duration<double>(Clock::now() - framing_start).count();
  apply_flips(wire);
  std::size_t at = 0;
  while (at < wire.size()) {
    // A socket never raises SIGPIPE here (a DUT that died is an error, not
    // the end of the harness); a pipe falls back to write().
    ssize_t w = ::send(write_fd_, wire.data() + at, wire.size() - at, MSG_NOSIGNAL);
    if (w < 0 && errno == ENOTSOCK) w = ::write(write_fd_, wire.data() + at, wire.size() - at);
    if (w > 0) {
      at += static_cast<std::size_t>(w);
      continue;
    }
    if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
      throw app::Error(name_ + ": write failed: " + std::strerror(errno));
    if (Clock::now() >= deadline) throw app::Error(name_ + ": send timed out (the device does not read)");
    pollfd p{write_fd_, POLLOUT, 0};
    ::poll(&p, 1, millis_until(deadline));
  }
  bytes_sent_ += wire.size();
}

std::optional<std::vector<std::byte>> StreamTransport::receive(Clock::time_point deadline) {
  for (;;) {
    const auto framing_start = Clock::now();
    while (pending_at_ < pending_.size()) {
      const std::byte b = pending_[pending_at_++];
      if (decoder_.push(b) == link::CobsStreamDecoder::Event::kMessage) {
        const auto m = decoder_.message();
        framing_seconds_ += std::chrono::duration<double>(Clock::now() - framing_start).count();
        return std::vector<std::byte>(m.begin(), m.end());
      }
    }
    framing_seconds_ += std::chrono::duration<double>(Clock::now() - framing_start).count();
    pending_.resize(65536);
    pending_at_ = 0;
    const ssize_t r = ::read(read_fd_, pending_.data(), pending_.size());
    if (r > 0) {
      pending_.resize(static_cast<std::size_t>(r));
      continue;
    }
    pending_.clear();
    if (r == 0) throw app::Error(name_ + ": the device closed the link");
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) throw app::Error(name_ + ": read failed: " + std::strerror(errno));
    if (Clock::now() >= deadline) return std::nullopt;
    pollfd p{read_fd_, POLLIN, 0};
    ::poll(&p, 1, millis_until(deadline));
  }
}

UdpTransport::UdpTransport(const std::string& host, std::uint16_t peer_port, std::uint16_t local_port)
    : fd_(::socket(AF_INET, SOCK_DGRAM, 0)), host_(host), peer_port_(peer_port) {
  if (fd_ < 0) throw app::Error(std::string("udp: socket: ") + std::strerror(errno));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(local_port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const int e = errno;
    ::close(fd_);
    throw app::Error("udp: bind port " + std::to_string(local_port) + ": " + std::strerror(e));
  }
  socklen_t len = sizeof a;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
  local_port_ = ntohs(a.sin_port);
  int size = 4 << 20;  // a burst of fragments must not overflow the receive buffer
  ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);
  ::setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
  set_nonblocking(fd_);
}

UdpTransport::~UdpTransport() { ::close(fd_); }

void UdpTransport::send(std::span<const std::byte> message, Clock::time_point deadline) {
  std::vector<std::byte> wire(message.begin(), message.end());
  apply_flips(wire);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(peer_port_);
  if (::inet_pton(AF_INET, host_.c_str(), &a.sin_addr) != 1) throw app::Error("udp: bad address '" + host_ + "'");
  for (;;) {
    const ssize_t w = ::sendto(fd_, wire.data(), wire.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof a);
    if (w == static_cast<ssize_t>(wire.size())) break;
    if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNREFUSED)
      throw app::Error(std::string("udp: sendto: ") + std::strerror(errno));
    if (Clock::now() >= deadline) throw app::Error("udp: send timed out");
    pollfd p{fd_, POLLOUT, 0};
    ::poll(&p, 1, millis_until(deadline));
  }
  bytes_sent_ += wire.size();
}

std::optional<std::vector<std::byte>> UdpTransport::receive(Clock::time_point deadline) {
  std::vector<std::byte> buffer(link::message_bytes(link::kMaxPayload) + 1);
  for (;;) {
    const ssize_t r = ::recv(fd_, buffer.data(), buffer.size(), 0);
    if (r >= 0) {
      buffer.resize(static_cast<std::size_t>(r));
      return buffer;
    }
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNREFUSED)
      throw app::Error(std::string("udp: recv: ") + std::strerror(errno));
    if (Clock::now() >= deadline) return std::nullopt;
    pollfd p{fd_, POLLIN, 0};
    ::poll(&p, 1, millis_until(deadline));
  }
}

Loopback::Loopback() : state_(std::make_shared<LoopbackState>()) {}
std::unique_ptr<Loopback::End> Loopback::host_end() { return std::unique_ptr<End>(new End(state_, 1)); }
std::unique_ptr<Loopback::End> Loopback::device_end() { return std::unique_ptr<End>(new End(state_, 0)); }

void Loopback::close() {
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    state_->closed = true;
  }
  state_->ready.notify_all();
}

void Loopback::End::send(std::span<const std::byte> message, Clock::time_point) {
  std::vector<std::byte> wire(message.begin(), message.end());
  apply_flips(wire);
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    if (state_->closed) throw app::Error("loopback: closed");
    state_->queue[side_ == 1 ? 0 : 1].push_back(std::move(wire));
  }
  bytes_sent_ += message.size();
  state_->ready.notify_all();
}

std::optional<std::vector<std::byte>> Loopback::End::receive(Clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(state_->mutex);
  auto& q = state_->queue[side_ == 1 ? 1 : 0];
  if (!state_->ready.wait_until(lock, deadline, [&] { return !q.empty() || state_->closed; })) return std::nullopt;
  if (q.empty()) throw app::Error("loopback: closed");
  std::vector<std::byte> m = std::move(q.front());
  q.pop_front();
  return m;
}

}  // namespace gabarit::hil
