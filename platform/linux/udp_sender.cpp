#include "udp_sender.hpp"

#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace gabarit::board {

UdpSender::~UdpSender() {
  if (fd_ >= 0) ::close(fd_);
}

bool UdpSender::open(const std::string& destination) {
  const std::size_t colon = destination.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == destination.size()) {
    error_ = "--udp '" + destination + "': want HOST:PORT";
    return false;
  }
  std::string host = destination.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  const std::string port = destination.substr(colon + 1);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  hints.ai_flags = AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(host.c_str(), port.c_str(), &hints, &found); rc != 0) {
    error_ = "--udp '" + destination + "': " + ::gai_strerror(rc);
    return false;
  }
  for (addrinfo* a = found; a != nullptr && fd_ < 0; a = a->ai_next) {
    fd_ = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
    if (fd_ >= 0 && ::connect(fd_, a->ai_addr, a->ai_addrlen) < 0) {
      error_ = "--udp '" + destination + "': " + std::strerror(errno);
      ::close(fd_);
      fd_ = -1;
    }
  }
  ::freeaddrinfo(found);
  return fd_ >= 0;
}

void UdpSender::send(const std::string& line) {
  if (fd_ < 0) return;
  if (::send(fd_, line.data(), line.size(), MSG_NOSIGNAL) < 0) ++failed_;
}

}  // namespace gabarit::board
