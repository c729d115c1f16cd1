// See usb_host.hpp. Each transfer is submitted asynchronously and waited for
// with libusb_handle_events_timeout_completed, so a transfer always ends: by
// completing, by its own timeout, or by being cancelled at a hard deadline.
#include "gabarit/link/usb_host.hpp"

#include <libusb-1.0/libusb.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace gabarit::link {

bool parse_usb_identity(const std::string& text, UsbIdentity& out, std::string& error) {
  const auto first = text.find(':');
  if (first == std::string::npos) {
    error = "'" + text + "': want VID:PID[:SERIAL] (hexadecimal IDs)";
    return false;
  }
  const auto second = text.find(':', first + 1);
  const std::string vid = text.substr(0, first);
  const std::string pid = text.substr(first + 1, second == std::string::npos ? std::string::npos : second - first - 1);
  const auto hex16 = [](std::string s, std::uint16_t& v) {
    if (s.rfind("0x", 0) == 0 || s.rfind("0X", 0) == 0) s.erase(0, 2);
    if (s.empty() || s.size() > 4) return false;
    char* end = nullptr;
    const unsigned long n = std::strtoul(s.c_str(), &end, 16);
    if (end == nullptr || *end != '\0') return false;
    v = static_cast<std::uint16_t>(n);
    return true;
  };
  UsbIdentity id;
  if (!hex16(vid, id.vendor_id) || !hex16(pid, id.product_id)) {
    error = "'" + text + "': the vendor and product IDs are 1 to 4 hexadecimal digits (0x optional)";
    return false;
  }
  if (second != std::string::npos) id.serial = text.substr(second + 1);
  out = id;
  return true;
}

namespace {

void on_transfer_done(libusb_transfer* transfer) { *static_cast<int*>(transfer->user_data) = 1; }

}  // namespace

UsbHostLink::UsbHostLink(UsbIdentity identity, std::size_t max_message)
    : identity_(std::move(identity)), max_message_(max_message) {
  if (const int r = libusb_init(&context_); r != 0) {
    context_ = nullptr;
    error_ = std::string("libusb_init: ") + libusb_error_name(r);
    return;
  }
  transfer_ = libusb_alloc_transfer(0);
  if (transfer_ == nullptr) error_ = "libusb_alloc_transfer failed";
}

UsbHostLink::~UsbHostLink() {
  close();
  if (transfer_ != nullptr) libusb_free_transfer(transfer_);
  if (context_ != nullptr) libusb_exit(context_);
}

void UsbHostLink::close() {
  if (handle_ == nullptr) return;
  if (interface_ >= 0) (void)libusb_release_interface(handle_, interface_);
  libusb_close(handle_);
  handle_ = nullptr;
  interface_ = -1;
  partial_.clear();
}

void UsbHostLink::lost(const char* what, int code) {
  ++stats_.losses;
  error_ = std::string(what) + ": " + libusb_error_name(code);
  close();
}

bool UsbHostLink::open() {
  if (handle_ != nullptr) return true;
  if (context_ == nullptr || transfer_ == nullptr) return false;
  // libusb keeps its device list current through hotplug events, which its
  // udev backend only gets from a running udevd: a bare board has none, so
  // each attempt starts a new context, which enumerates sysfs afresh.
  libusb_exit(context_);
  context_ = nullptr;
  if (const int r = libusb_init(&context_); r != 0) {
    context_ = nullptr;
    error_ = std::string("libusb_init: ") + libusb_error_name(r);
    return false;
  }
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(context_, &list);
  if (n < 0) {
    error_ = std::string("listing USB devices: ") + libusb_error_name(static_cast<int>(n));
    return false;
  }
  error_ = "no USB device " + [&] {
    char id[16];
    std::snprintf(id, sizeof id, "%04x:%04x", identity_.vendor_id, identity_.product_id);
    return std::string(id);
  }() + (identity_.serial.empty() ? std::string() : " with serial " + identity_.serial);
  std::string seen;
  for (ssize_t i = 0; i < n && handle_ == nullptr; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    char id[16];
    std::snprintf(id, sizeof id, " %04x:%04x", d.idVendor, d.idProduct);
    seen += id;
    if (d.idVendor != identity_.vendor_id || d.idProduct != identity_.product_id) continue;
    libusb_device_handle* h = nullptr;
    if (const int r = libusb_open(list[i], &h); r != 0) {
      error_ = std::string("opening the device: ") + libusb_error_name(r);
      continue;
    }
    unsigned char text[128] = {};
    std::string serial, product;
    if (d.iSerialNumber != 0 && libusb_get_string_descriptor_ascii(h, d.iSerialNumber, text, sizeof text) > 0)
      serial = reinterpret_cast<const char*>(text);
    if (d.iProduct != 0 && libusb_get_string_descriptor_ascii(h, d.iProduct, text, sizeof text) > 0)
      product = reinterpret_cast<const char*>(text);
    if (!identity_.serial.empty() && serial != identity_.serial) {
      libusb_close(h);
      seen += " (serial '" + serial + "')";
      continue;
    }
    // The first interface with a bulk endpoint each way.
    libusb_config_descriptor* config = nullptr;
    if (libusb_get_active_config_descriptor(list[i], &config) != 0 || config == nullptr) {
      libusb_close(h);
      error_ = "the device has no active configuration (yet)";
      continue;
    }
    for (int k = 0; k < config->bNumInterfaces && interface_ < 0; ++k) {
      if (config->interface[k].num_altsetting < 1) continue;
      const libusb_interface_descriptor& alt = config->interface[k].altsetting[0];
      unsigned char in = 0, out = 0;
      std::uint16_t pin = 0, pout = 0;
      for (int e = 0; e < alt.bNumEndpoints; ++e) {
        const libusb_endpoint_descriptor& ep = alt.endpoint[e];
        if ((ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK) continue;
        if ((ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) != 0) in = ep.bEndpointAddress, pin = ep.wMaxPacketSize;
        else out = ep.bEndpointAddress, pout = ep.wMaxPacketSize;
      }
      if (in != 0 && out != 0) {
        interface_ = alt.bInterfaceNumber;
        ep_in_ = in, ep_out_ = out, packet_in_ = pin, packet_out_ = pout;
      }
    }
    libusb_free_config_descriptor(config);
    if (interface_ < 0) {
      libusb_close(h);
      error_ = "the device has no interface with bulk IN and OUT endpoints";
      continue;
    }
    (void)libusb_set_auto_detach_kernel_driver(h, 1);
    if (const int r = libusb_claim_interface(h, interface_); r != 0) {
      libusb_close(h);
      interface_ = -1;
      error_ = std::string("claiming the interface: ") + libusb_error_name(r);
      continue;
    }
    handle_ = h;
    serial_ = serial;
    product_ = product;
  }
  libusb_free_device_list(list, 1);
  if (handle_ == nullptr) {
    error_ += seen.empty() ? " (no USB devices at all)" : " (devices:" + seen + ")";
    return false;
  }
  ++stats_.opens;
  error_.clear();
  // A multiple of the packet size, so a device's full packets never overflow it.
  const std::size_t packet = std::max<std::size_t>(packet_in_, 64);
  in_buffer_.assign((max_message_ / packet + 1) * packet, 0);
  out_buffer_.assign(max_message_, 0);
  partial_.clear();
  return true;
}

UsbHostLink::Done UsbHostLink::run_transfer(unsigned char endpoint, unsigned char* data, int length, unsigned timeout_ms,
                                            bool zero_packet, int& transferred) {
  transferred = 0;
  int completed = 0;
  libusb_fill_bulk_transfer(transfer_, handle_, endpoint, data, length, on_transfer_done, &completed, timeout_ms);
  transfer_->flags = zero_packet ? LIBUSB_TRANSFER_ADD_ZERO_PACKET : 0;
  if (const int r = libusb_submit_transfer(transfer_); r != 0) {
    if (r == LIBUSB_ERROR_PIPE) return Done::kStall;
    lost("submitting a transfer", r);
    return Done::kGone;
  }
  // libusb expires the transfer at timeout_ms; past a second more, cancel it
  // ourselves (a stuck host controller must not hang the caller).
  const auto hard_deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms + 1000);
  bool cancelled = false;
  while (completed == 0) {
    timeval tv{0, 100000};
    const int r = libusb_handle_events_timeout_completed(context_, &tv, &completed);
    if (r != 0 && r != LIBUSB_ERROR_INTERRUPTED && r != LIBUSB_ERROR_TIMEOUT && !cancelled) {
      (void)libusb_cancel_transfer(transfer_);
      cancelled = true;
    }
    if (!cancelled && std::chrono::steady_clock::now() > hard_deadline) {
      (void)libusb_cancel_transfer(transfer_);
      cancelled = true;
    }
  }
  transferred = transfer_->actual_length;
  switch (transfer_->status) {
    case LIBUSB_TRANSFER_COMPLETED: return Done::kCompleted;
    case LIBUSB_TRANSFER_TIMED_OUT: return Done::kTimedOut;
    case LIBUSB_TRANSFER_CANCELLED: return Done::kTimedOut;  // our hard deadline
    case LIBUSB_TRANSFER_STALL: return Done::kStall;
    case LIBUSB_TRANSFER_NO_DEVICE: lost("transfer", LIBUSB_ERROR_NO_DEVICE); return Done::kGone;
    case LIBUSB_TRANSFER_OVERFLOW: ++stats_.oversize; return Done::kCompleted;
    case LIBUSB_TRANSFER_ERROR:
    default: lost("transfer", LIBUSB_ERROR_IO); return Done::kGone;
  }
}

UsbResult UsbHostLink::send(std::span<const std::byte> message, unsigned timeout_ms) {
  if (handle_ == nullptr) return UsbResult::kGone;
  if (message.size() > out_buffer_.size()) out_buffer_.resize(message.size());
  std::memcpy(out_buffer_.data(), message.data(), message.size());
  const bool zlp = packet_out_ != 0 && message.size() % packet_out_ == 0;
  for (int attempt = 0; attempt < 2; ++attempt) {
    int moved = 0;
    switch (run_transfer(ep_out_, out_buffer_.data(), static_cast<int>(message.size()), timeout_ms, zlp, moved)) {
      case Done::kCompleted:
        ++stats_.messages_out;
        if (zlp) ++stats_.zero_length_out;
        return UsbResult::kOk;
      case Done::kTimedOut:
        ++stats_.timeouts;
        if (moved > 0) ++stats_.partial_timeouts;  // the device holds part of a message: its CRC check drops it
        return UsbResult::kTimeout;
      case Done::kStall:
        if (const int r = libusb_clear_halt(handle_, ep_out_); r != 0) {
          lost("clearing a halt", r);
          return UsbResult::kGone;
        }
        ++stats_.halts_cleared;
        continue;
      case Done::kGone: return UsbResult::kGone;
    }
  }
  return UsbResult::kTimeout;
}

UsbResult UsbHostLink::receive(std::vector<std::byte>& out, unsigned timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    if (handle_ == nullptr) return UsbResult::kGone;
    const auto now = std::chrono::steady_clock::now();
    const auto left = deadline > now ? std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now).count() : 0;
    int moved = 0;
    const Done done = run_transfer(ep_in_, in_buffer_.data(), static_cast<int>(in_buffer_.size()),
                                   static_cast<unsigned>(std::max<long long>(left, 1)), false, moved);
    if (moved > 0) {
      const auto* p = reinterpret_cast<const std::byte*>(in_buffer_.data());
      partial_.insert(partial_.end(), p, p + moved);
    }
    switch (done) {
      case Done::kCompleted:
        // A short (or zero-length) packet ends a message; a full buffer is
        // longer than any message (its CRC check rejects it).
        if (partial_.empty()) {
          ++stats_.empty_in;
          break;
        }
        if (static_cast<std::size_t>(moved) == in_buffer_.size()) ++stats_.oversize;
        out.swap(partial_);
        partial_.clear();
        ++stats_.messages_in;
        return UsbResult::kOk;
      case Done::kTimedOut:
        ++stats_.timeouts;
        // A short packet ended the message just as the transfer expired: it
        // is whole. A run of full packets may go on in the next transfer.
        if (moved > 0 && packet_in_ != 0 && static_cast<std::size_t>(moved) % packet_in_ != 0) {
          out.swap(partial_);
          partial_.clear();
          ++stats_.messages_in;
          return UsbResult::kOk;
        }
        if (moved > 0) ++stats_.partial_timeouts;
        return UsbResult::kTimeout;
      case Done::kStall:
        if (const int r = libusb_clear_halt(handle_, ep_in_); r != 0) {
          lost("clearing a halt", r);
          return UsbResult::kGone;
        }
        ++stats_.halts_cleared;
        break;
      case Done::kGone: return UsbResult::kGone;
    }
    if (std::chrono::steady_clock::now() >= deadline) return UsbResult::kTimeout;
  }
}

bool UsbHostLink::halt_in_endpoint() {
  if (handle_ == nullptr) return false;
  const int r = libusb_control_transfer(handle_, 0x02 /* host to device, standard, endpoint */,
                                        LIBUSB_REQUEST_SET_FEATURE, 0 /* ENDPOINT_HALT */, ep_in_, nullptr, 0, 1000);
  if (r < 0) {
    error_ = std::string("SET_FEATURE(ENDPOINT_HALT): ") + libusb_error_name(r);
    return false;
  }
  return true;
}

}  // namespace gabarit::link
