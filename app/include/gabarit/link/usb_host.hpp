// The host side of the HIL link over USB (libusb-1.0's asynchronous API): a
// vendor interface with one bulk IN and one bulk OUT endpoint, one protocol
// message per transfer (docs/hil-protocol.md, "USB"). Shared by the harness
// (a real board, --dut board:NAME) and the virtual board's relay, which runs
// on the board's side of dummy_hcd; the device side is
// platform/linux/usb_gadget.hpp (FunctionFS).
//
// What the transport does about USB's failure modes:
//   - every transfer has a finite timeout; a timed-out IN transfer may have
//     moved part of a message: the bytes are kept and the next transfer
//     continues the message (it ends at a short or zero-length packet);
//   - an OUT message whose length is a multiple of the endpoint's packet size
//     is ended by a zero-length packet (LIBUSB_TRANSFER_ADD_ZERO_PACKET);
//   - LIBUSB_ERROR_PIPE (a halted endpoint) clears the halt and retries once;
//   - NO_DEVICE, IO and any other error close the device: the caller reopens
//     it by polling open() (no hotplug: a bare board has no udev).
// Hosted code: allocates, never throws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

struct libusb_context;
struct libusb_device_handle;
struct libusb_transfer;

namespace gabarit::link {

// The device's stable identity. The defaults are the project's: a vendor
// ID from the range Linux's own test gadgets use, a product ID of ours.
struct UsbIdentity {
  std::uint16_t vendor_id = 0x1d6b;   // Linux Foundation (the gadget framework's test IDs)
  std::uint16_t product_id = 0x0104;  // "Multifunction Composite Gadget"; a product gets its own
  std::string serial;                 // "" matches any serial
};
// "VID:PID[:SERIAL]", hexadecimal IDs; false with `error` for anything else.
bool parse_usb_identity(const std::string& text, UsbIdentity& out, std::string& error);

struct UsbHostStats {
  std::uint64_t messages_in = 0, messages_out = 0;
  std::uint64_t timeouts = 0;          // transfers that expired
  std::uint64_t partial_timeouts = 0;  // ... having moved part of a message
  std::uint64_t zero_length_out = 0;   // OUT messages ended by a zero-length packet
  std::uint64_t empty_in = 0;          // zero-length IN transfers (a message's end, or nothing)
  std::uint64_t halts_cleared = 0;     // LIBUSB_ERROR_PIPE answered by clear-halt
  std::uint64_t opens = 0, losses = 0; // device opened; device gone (NO_DEVICE, IO, ...)
  std::uint64_t oversize = 0;          // IN messages longer than the buffer, discarded
};

enum class [[nodiscard]] UsbResult { kOk, kTimeout, kGone };

class UsbHostLink {
 public:
  // `max_message` bounds a message (the protocol's message_bytes(max payload)).
  UsbHostLink(UsbIdentity identity, std::size_t max_message);
  ~UsbHostLink();
  UsbHostLink(const UsbHostLink&) = delete;
  UsbHostLink& operator=(const UsbHostLink&) = delete;

  // libusb initialised (false: error() says why; nothing else works).
  bool ready() const { return context_ != nullptr; }
  // Looks for the device now and opens it: claims the first interface with
  // a bulk IN and a bulk OUT endpoint. false: not there (yet), or error().
  bool open();
  bool is_open() const { return handle_ != nullptr; }
  void close();

  // One message as one transfer, by `timeout_ms`.
  UsbResult send(std::span<const std::byte> message, unsigned timeout_ms);
  // The next whole message into `out`, or kTimeout by `timeout_ms` (a part
  // of one may have arrived and is kept), or kGone.
  UsbResult receive(std::vector<std::byte>& out, unsigned timeout_ms);

  // A fault for tests: the host halts the device's IN endpoint
  // (SET_FEATURE(ENDPOINT_HALT)); the next IN transfer then fails with
  // LIBUSB_ERROR_PIPE, which this transport must clear.
  bool halt_in_endpoint();

  const UsbHostStats& stats() const { return stats_; }
  const std::string& error() const { return error_; }
  const std::string& serial() const { return serial_; }    // of the open device
  const std::string& product() const { return product_; }

 private:
  enum class Done { kCompleted, kTimedOut, kStall, kGone };
  Done run_transfer(unsigned char endpoint, unsigned char* data, int length, unsigned timeout_ms, bool zero_packet,
                    int& transferred);
  void lost(const char* what, int code);

  UsbIdentity identity_;
  std::size_t max_message_;
  libusb_context* context_ = nullptr;
  libusb_device_handle* handle_ = nullptr;
  libusb_transfer* transfer_ = nullptr;
  int interface_ = -1;
  unsigned char ep_in_ = 0, ep_out_ = 0;
  std::uint16_t packet_in_ = 0, packet_out_ = 0;
  std::vector<unsigned char> in_buffer_, out_buffer_;
  std::vector<std::byte> partial_;  // bytes of a message that a timeout interrupted
  UsbHostStats stats_;
  std::string error_, serial_, product_;
};

}  // namespace gabarit::link
