// The board's side of the HIL link over USB: a FunctionFS function with one
// bulk IN and one bulk OUT endpoint (a vendor-specific interface), one link
// message per transfer, ended by a zero-length packet when its length is a
// multiple of 64 bytes (every full- and high-speed packet size divides it).
//
// configfs creates the gadget and its identity (vendor, product, serial:
// platform/linux/usb-gadget.sh); this class writes the function's
// descriptors to ep0, opens the endpoints and, given the gadget's configfs
// folder, binds it to the UDC, which the kernel requires to happen after
// the descriptors. The kernel unbinds the gadget when ep0 closes (the
// program exits or is killed), so a restarted board binds it again.
//
// FunctionFS endpoint files block and cannot be polled, so a thread reads
// OUT, a thread writes IN and a thread reads ep0's events (bind, enable,
// disable: the host's configuration and the cable). The owner waits on
// event_fd() and takes what arrived; sending never blocks (a bounded queue).
#pragma once

#include <pthread.h>

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

namespace gabarit::board {

struct UsbGadgetOptions {
  std::string ffs_dir;     // the mounted FunctionFS instance (holds ep0)
  std::string gadget_dir;  // its configfs gadget, to bind once ready ("": bound by someone else)
  std::string udc = "auto";  // with gadget_dir: the controller's name, or the first in /sys/class/udc
  std::string interface_name = "gabarit HIL link";
  std::size_t max_message = 0;  // the longest message either way
  std::size_t send_queue = 256; // messages waiting for the host, at most
};

struct UsbGadgetStats {
  std::uint64_t messages_in = 0, messages_out = 0, zero_length_out = 0;
  std::uint64_t enables = 0, disables = 0;  // the host configured us / the cable or host went
  std::uint64_t write_errors = 0;           // a message the host never took (unplugged meanwhile)
  std::uint64_t queue_full = 0;             // a message not queued: the host reads nothing
  std::uint64_t setups_stalled = 0;         // control requests for the function: none is defined
};

class UsbGadget {
 public:
  UsbGadget() = default;
  ~UsbGadget();
  UsbGadget(const UsbGadget&) = delete;
  UsbGadget& operator=(const UsbGadget&) = delete;

  // false with error(): no FunctionFS there, descriptors refused, no UDC.
  bool open(const UsbGadgetOptions& options);
  void close();
  // Readable (an eventfd) when messages arrived or the link state changed.
  int event_fd() const { return event_fd_; }
  void clear_event();
  // The next received message (one OUT transfer); false: none.
  bool receive(std::vector<std::byte>& message);
  // Queues one message for the host; false (counted) when the queue is full.
  bool send(std::span<const std::byte> message);
  // The host has configured the function (and it was not disabled since).
  bool enabled() const { return enabled_.load(); }
  // Enables so far: a change tells the owner the link came back.
  std::uint64_t enable_count() const { return enables_.load(); }
  UsbGadgetStats stats() const;
  const std::string& error() const { return error_; }

 private:
  void ep0_loop();
  void reader_loop();
  void writer_loop();
  void notify();
  bool bind_udc();

  UsbGadgetOptions options_;
  int ep0_ = -1, ep_in_ = -1, ep_out_ = -1, event_fd_ = -1;
  std::thread ep0_thread_, reader_, writer_;
  std::atomic<bool> stopping_{false}, enabled_{false};
  std::atomic<int> exited_{0};
  std::atomic<std::uint64_t> enables_{0};
  mutable std::mutex mutex_;
  std::condition_variable to_send_;
  std::deque<std::vector<std::byte>> inbox_, outbox_;
  UsbGadgetStats stats_;
  std::string error_;
};

}  // namespace gabarit::board
