// See usb_gadget.hpp.
#include "usb_gadget.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <endian.h>

namespace gabarit::board {

namespace {

// The interface: vendor-specific class, two bulk endpoints (ep1 IN, ep2 OUT:
// FunctionFS names the endpoint files in descriptor order).
struct __attribute__((packed)) Interface {
  usb_interface_descriptor intf;
  usb_endpoint_descriptor_no_audio in, out;
};
struct __attribute__((packed)) Descriptors {
  usb_functionfs_descs_head_v2 header;
  __le32 fs_count, hs_count;
  Interface fs, hs;
};

Interface interface_descriptors(std::uint16_t packet) {
  Interface d{};
  d.intf.bLength = sizeof d.intf;
  d.intf.bDescriptorType = USB_DT_INTERFACE;
  d.intf.bNumEndpoints = 2;
  d.intf.bInterfaceClass = USB_CLASS_VENDOR_SPEC;
  d.intf.iInterface = 1;
  for (auto* ep : {&d.in, &d.out}) {
    ep->bLength = sizeof *ep;
    ep->bDescriptorType = USB_DT_ENDPOINT;
    ep->bmAttributes = USB_ENDPOINT_XFER_BULK;
    ep->wMaxPacketSize = htole16(packet);
  }
  d.in.bEndpointAddress = 1 | USB_DIR_IN;
  d.out.bEndpointAddress = 2 | USB_DIR_OUT;
  return d;
}

// `stop`, when set, ends a write interrupted by a signal.
bool write_all(int fd, const void* data, std::size_t n, const std::atomic<bool>* stop = nullptr) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR && (stop == nullptr || !*stop)) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

bool write_text_file(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = write_all(fd, text.data(), text.size());
  ::close(fd);
  return ok;
}

// Wakes a thread blocked in an endpoint read or write (EINTR): no handler
// work, and without SA_RESTART so the system call returns.
void on_wake_signal(int) {}
constexpr int kWakeSignal = SIGUSR1;

}  // namespace

UsbGadget::~UsbGadget() { close(); }

bool UsbGadget::open(const UsbGadgetOptions& options) {
  close();
  options_ = options;
  stopping_ = false;
  struct sigaction sa{};
  sa.sa_handler = on_wake_signal;
  sigemptyset(&sa.sa_mask);
  ::sigaction(kWakeSignal, &sa, nullptr);

  const std::string ep0 = options.ffs_dir + "/ep0";
  ep0_ = ::open(ep0.c_str(), O_RDWR | O_CLOEXEC);
  if (ep0_ < 0) {
    error_ = "opening " + ep0 + ": " + std::strerror(errno) + " (is FunctionFS mounted there?)";
    return false;
  }
  Descriptors d{};
  d.header.magic = htole32(FUNCTIONFS_DESCRIPTORS_MAGIC_V2);
  d.header.length = htole32(sizeof d);
  d.header.flags = htole32(FUNCTIONFS_HAS_FS_DESC | FUNCTIONFS_HAS_HS_DESC);
  d.fs_count = d.hs_count = htole32(3);
  d.fs = interface_descriptors(64);
  d.hs = interface_descriptors(512);
  // The strings: one language (en-US), the interface's name.
  std::vector<std::uint8_t> strings(sizeof(usb_functionfs_strings_head) + 2 + options.interface_name.size() + 1, 0);
  usb_functionfs_strings_head head{};
  head.magic = htole32(FUNCTIONFS_STRINGS_MAGIC);
  head.length = htole32(static_cast<std::uint32_t>(strings.size()));
  head.str_count = htole32(1);
  head.lang_count = htole32(1);
  std::memcpy(strings.data(), &head, sizeof head);
  const std::uint16_t lang = htole16(0x0409);
  std::memcpy(strings.data() + sizeof head, &lang, 2);
  std::memcpy(strings.data() + sizeof head + 2, options.interface_name.c_str(), options.interface_name.size());
  if (!write_all(ep0_, &d, sizeof d) || !write_all(ep0_, strings.data(), strings.size())) {
    error_ = "FunctionFS refused the descriptors: " + std::string(std::strerror(errno));
    close();
    return false;
  }
  ep_in_ = ::open((options.ffs_dir + "/ep1").c_str(), O_RDWR | O_CLOEXEC);
  ep_out_ = ::open((options.ffs_dir + "/ep2").c_str(), O_RDWR | O_CLOEXEC);
  event_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (ep_in_ < 0 || ep_out_ < 0 || event_fd_ < 0) {
    error_ = "opening the endpoints: " + std::string(std::strerror(errno));
    close();
    return false;
  }
  if (!options.gadget_dir.empty() && !bind_udc()) {
    close();
    return false;
  }
  exited_ = 0;
  ep0_thread_ = std::thread([this] { ep0_loop(); ++exited_; });
  reader_ = std::thread([this] { reader_loop(); ++exited_; });
  writer_ = std::thread([this] { writer_loop(); ++exited_; });
  return true;
}

bool UsbGadget::bind_udc() {
  std::string udc = options_.udc;
  if (udc.empty() || udc == "auto") {
    udc.clear();
    if (DIR* dir = ::opendir("/sys/class/udc")) {
      while (const dirent* e = ::readdir(dir))
        if (e->d_name[0] != '.') {
          udc = e->d_name;
          break;
        }
      ::closedir(dir);
    }
    if (udc.empty()) {
      error_ = "no USB device controller in /sys/class/udc (dummy_hcd or the board's UDC driver not loaded?)";
      return false;
    }
  }
  const std::string path = options_.gadget_dir + "/UDC";
  if (write_text_file(path, udc + "\n")) return true;
  if (errno == EBUSY) return true;  // already bound (by an earlier run that did not close ep0)
  error_ = "binding " + path + " to " + udc + ": " + std::strerror(errno);
  return false;
}

void UsbGadget::close() {
  stopping_ = true;
  to_send_.notify_all();
  // A thread may be blocked in an endpoint call: signal the threads until
  // all three are out of their loops (each tests stopping_ after every call).
  const int running = (ep0_thread_.joinable() ? 1 : 0) + (reader_.joinable() ? 1 : 0) + (writer_.joinable() ? 1 : 0);
  while (exited_.load() < running) {
    for (std::thread* t : {&ep0_thread_, &reader_, &writer_})
      if (t->joinable()) ::pthread_kill(t->native_handle(), kWakeSignal);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  for (std::thread* t : {&ep0_thread_, &reader_, &writer_})
    if (t->joinable()) t->join();
  exited_ = 0;
  for (int* fd : {&ep_in_, &ep_out_, &ep0_, &event_fd_})
    if (*fd >= 0) ::close(*fd), *fd = -1;
  enabled_ = false;
  std::lock_guard lock(mutex_);
  inbox_.clear();
  outbox_.clear();
}

void UsbGadget::notify() {
  const std::uint64_t one = 1;
  if (event_fd_ >= 0) (void)!::write(event_fd_, &one, sizeof one);
}

void UsbGadget::clear_event() {
  std::uint64_t v;
  if (event_fd_ >= 0) (void)!::read(event_fd_, &v, sizeof v);
}

void UsbGadget::ep0_loop() {
  usb_functionfs_event events[4];
  while (!stopping_) {
    const ssize_t n = ::read(ep0_, events, sizeof events);
    if (n < 0) {
      if (errno != EINTR && errno != EAGAIN) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(n) / sizeof events[0]; ++i) {
      switch (events[i].type) {
        case FUNCTIONFS_ENABLE:
          enabled_ = true;
          ++enables_;
          {
            std::lock_guard lock(mutex_);
            ++stats_.enables;
          }
          to_send_.notify_all();
          notify();
          break;
        case FUNCTIONFS_DISABLE:
        case FUNCTIONFS_UNBIND:
          if (enabled_.exchange(false)) {
            std::lock_guard lock(mutex_);
            ++stats_.disables;
          }
          notify();
          break;
        case FUNCTIONFS_SETUP: {
          // No control request is defined for this function: stall it, by
          // doing the transfer's data stage in the wrong direction.
          std::uint8_t dummy = 0;
          if ((events[i].u.setup.bRequestType & USB_DIR_IN) != 0) (void)!::read(ep0_, &dummy, 0);
          else (void)!::write(ep0_, &dummy, 0);
          std::lock_guard lock(mutex_);
          ++stats_.setups_stalled;
          break;
        }
        default: break;  // BIND, SUSPEND, RESUME: nothing to do
      }
    }
  }
}

void UsbGadget::reader_loop() {
  // FunctionFS rounds a read up to the packet size; room for any message.
  std::vector<std::byte> buffer((options_.max_message / 512 + 1) * 512);
  while (!stopping_) {
    const ssize_t n = ::read(ep_out_, buffer.data(), buffer.size());
    if (n > 0) {
      {
        std::lock_guard lock(mutex_);
        inbox_.emplace_back(buffer.begin(), buffer.begin() + n);
        ++stats_.messages_in;
      }
      notify();
    } else if (n < 0 && errno != EINTR) {
      // ESHUTDOWN and the like: the host went away; the read waits for it
      // again once the function is enabled.
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
}

void UsbGadget::writer_loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    to_send_.wait(lock, [&] { return stopping_ || (!outbox_.empty() && enabled_); });
    if (stopping_) break;
    std::vector<std::byte> m = std::move(outbox_.front());
    outbox_.pop_front();
    lock.unlock();
    bool ok = write_all(ep_in_, m.data(), m.size(), &stopping_);
    const bool zlp = ok && m.size() % 64 == 0;
    if (zlp) ok = ::write(ep_in_, m.data(), 0) == 0;
    lock.lock();
    if (ok) {
      ++stats_.messages_out;
      if (zlp) ++stats_.zero_length_out;
    } else {
      ++stats_.write_errors;  // the link layer resends what the host never acknowledged
    }
  }
}

bool UsbGadget::receive(std::vector<std::byte>& message) {
  std::lock_guard lock(mutex_);
  if (inbox_.empty()) return false;
  message = std::move(inbox_.front());
  inbox_.pop_front();
  return true;
}

bool UsbGadget::send(std::span<const std::byte> message) {
  {
    std::lock_guard lock(mutex_);
    if (outbox_.size() >= options_.send_queue) {
      ++stats_.queue_full;
      return false;
    }
    outbox_.emplace_back(message.begin(), message.end());
  }
  to_send_.notify_one();
  return true;
}

UsbGadgetStats UsbGadget::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace gabarit::board
