#include "device/dfu_flasher.hpp"

#include <libusb.h>

#include <algorithm>
#include <cstdio>
#include <thread>

#include "device/controller_client.hpp"
#include "device/usb_discovery.hpp"

namespace flutterscan::device {

namespace {

/// Control transfer timeout (an erase can take a while; bwPollTimeout covers the rest).
constexpr unsigned kControlTimeoutMs = 5000;
/// GETSTATUS polls allowed for one block or the manifest before giving up.
constexpr int kMaxPolls = 2000;
/// Between looks at the bus while waiting for a device to enumerate.
constexpr auto kEnumeratePoll = std::chrono::milliseconds(100);

void say(const FlashOptions& options, const std::string& line) {
  if (options.log) options.log(line);
}

std::string block_text(std::size_t block) {
  return "block " + std::to_string(block);
}

}  // namespace

std::string dfu_status_text(std::uint8_t status) {
  switch (static_cast<protocol::DfuStatus>(status)) {
    case protocol::DfuStatus::kOk:
      return "OK";
    case protocol::DfuStatus::kErrTarget:
      return "errTARGET: file is not targeted for this device";
    case protocol::DfuStatus::kErrFile:
      return "errFILE: file fails a vendor-specific check";
    case protocol::DfuStatus::kErrWrite:
      return "errWRITE: unable to write memory";
    case protocol::DfuStatus::kErrErase:
      return "errERASE: memory erase failed";
    case protocol::DfuStatus::kErrCheckErased:
      return "errCHECK_ERASED: memory erase check failed";
    case protocol::DfuStatus::kErrProg:
      return "errPROG: program memory failed";
    case protocol::DfuStatus::kErrVerify:
      return "errVERIFY: programmed memory failed verification";
    case protocol::DfuStatus::kErrAddress:
      return "errADDRESS: address out of range (blocks out of order?)";
    case protocol::DfuStatus::kErrNotDone:
      return "errNOTDONE: end of download before it was expected";
    case protocol::DfuStatus::kErrFirmware:
      return "errFIRMWARE: the image failed the bootloader's check (header, board, size or CRC)";
    case protocol::DfuStatus::kErrVendor:
      return "errVENDOR: the image's security version is below the newest confirmed image's on "
             "this controller (anti-rollback)";
    case protocol::DfuStatus::kErrUsbReset:
      return "errUSBR: unexpected USB reset";
    case protocol::DfuStatus::kErrPowerOnReset:
      return "errPOR: unexpected power-on reset";
    case protocol::DfuStatus::kErrUnknown:
      return "errUNKNOWN: unknown error";
    case protocol::DfuStatus::kErrStalledPacket:
      return "errSTALLEDPKT: unexpected request";
  }
  return "DFU status " + std::to_string(status);
}

const char* dfu_state_name(DfuState state) {
  switch (state) {
    case DfuState::kAppIdle:
      return "appIDLE";
    case DfuState::kAppDetach:
      return "appDETACH";
    case DfuState::kDfuIdle:
      return "dfuIDLE";
    case DfuState::kDnloadSync:
      return "dfuDNLOAD-SYNC";
    case DfuState::kDnBusy:
      return "dfuDNBUSY";
    case DfuState::kDnloadIdle:
      return "dfuDNLOAD-IDLE";
    case DfuState::kManifestSync:
      return "dfuMANIFEST-SYNC";
    case DfuState::kManifest:
      return "dfuMANIFEST";
    case DfuState::kManifestWaitReset:
      return "dfuMANIFEST-WAIT-RESET";
    case DfuState::kUploadIdle:
      return "dfuUPLOAD-IDLE";
    case DfuState::kError:
      return "dfuERROR";
  }
  return "unknown DFU state";
}

// ---------------------------------------------------------------------------
// The DFU request sequence

Expected<DfuStatusReply> dfu_get_status(DfuControl& dfu) {
  const auto reply = dfu.control_in(DfuRequest::kGetStatus, 0,
                                    static_cast<std::uint16_t>(protocol::kDfuStatusSize));
  if (!reply.ok()) return fail<DfuStatusReply>(reply.error());
  const auto& bytes = reply.value();
  if (bytes.size() != protocol::kDfuStatusSize)
    return fail<DfuStatusReply>(
        ErrorKind::kBadReply,
        "DFU GETSTATUS returned " + std::to_string(bytes.size()) + " bytes, expected 6");
  return Expected<DfuStatusReply>::success(
      protocol::parse_dfu_status(std::span<const std::uint8_t, protocol::kDfuStatusSize>(
          bytes.data(), protocol::kDfuStatusSize)));
}

Expected<Done> dfu_make_idle(DfuControl& dfu) {
  auto status = dfu_get_status(dfu);
  if (!status.ok()) return fail(status.error());
  if (status.value().state == DfuState::kDfuIdle) return done();
  const DfuRequest fix =
      status.value().state == DfuState::kError ? DfuRequest::kClrStatus : DfuRequest::kAbort;
  if (auto sent = dfu.control_out(fix, 0, {}); !sent.ok()) return sent;
  status = dfu_get_status(dfu);
  if (!status.ok()) return fail(status.error());
  if (status.value().state != DfuState::kDfuIdle)
    return fail(ErrorKind::kRejected,
                std::string("the bootloader stays in ") + dfu_state_name(status.value().state) +
                    " (" + dfu_status_text(static_cast<std::uint8_t>(status.value().status)) +
                    ") instead of dfuIDLE");
  return done();
}

namespace {

/// GETSTATUS until the state is one of `done_states`, sleeping bwPollTimeout
/// while it is one of `busy_states`.
Expected<DfuState> poll_until(DfuControl& dfu, std::initializer_list<DfuState> done_states,
                              std::initializer_list<DfuState> busy_states, const DfuSleeper& sleep,
                              const std::string& what) {
  std::chrono::milliseconds waited{0};
  for (int poll = 0; poll < kMaxPolls && waited <= kMaxDfuBusyWait; ++poll) {
    const auto status = dfu_get_status(dfu);
    if (!status.ok()) return fail<DfuState>(status.error());
    const DfuStatusReply s = status.value();
    // An image older than the controller allows is the caller's bad input (exit 2).
    if (s.state == DfuState::kError || s.status != protocol::DfuStatus::kOk)
      return fail<DfuState>(s.status == protocol::DfuStatus::kErrVendor ? ErrorKind::kBadInput
                                                                         : ErrorKind::kRejected,
                            "the bootloader refused " + what + ": " +
                                dfu_status_text(static_cast<std::uint8_t>(s.status)) + " (state " +
                                dfu_state_name(s.state) + ")");
    if (std::find(done_states.begin(), done_states.end(), s.state) != done_states.end())
      return Expected<DfuState>::success(s.state);
    if (std::find(busy_states.begin(), busy_states.end(), s.state) == busy_states.end())
      return fail<DfuState>(ErrorKind::kBadReply, std::string("unexpected DFU state ") +
                                                      dfu_state_name(s.state) + " after " + what);
    const auto nap = std::min(std::chrono::milliseconds(s.poll_timeout_ms), kMaxDfuPollSleep);
    sleep(nap);
    waited += nap;
  }
  return fail<DfuState>(ErrorKind::kTimeout, "the bootloader stayed busy after " + what);
}

}  // namespace

Expected<Done> dfu_download(DfuControl& dfu, std::span<const std::uint8_t> image,
                            const ProgressCallback& progress, const DfuSleeper& sleep) {
  if (auto idle = dfu_make_idle(dfu); !idle.ok()) return idle;
  const std::size_t blocks =
      (image.size() + protocol::kDfuTransferSize - 1) / protocol::kDfuTransferSize;
  if (blocks > 0xFFFF) return fail(ErrorKind::kBadInput, "image too large for DFU block numbers");
  if (progress) progress(0, image.size());
  for (std::size_t block = 0; block < blocks; ++block) {
    const std::size_t offset = block * protocol::kDfuTransferSize;
    const auto data = image.subspan(
        offset, std::min<std::size_t>(protocol::kDfuTransferSize, image.size() - offset));
    if (auto sent = dfu.control_out(DfuRequest::kDnload, static_cast<std::uint16_t>(block), data);
        !sent.ok())
      return fail(sent.error().kind, "DNLOAD " + block_text(block) + ": " + sent.error().message);
    const auto state =
        poll_until(dfu, {DfuState::kDnloadIdle}, {DfuState::kDnBusy, DfuState::kDnloadSync}, sleep,
                   block_text(block));
    if (!state.ok()) return fail(state.error());
    if (progress) progress(offset + data.size(), image.size());
  }
  // The zero-length DNLOAD ends the download; GETSTATUS then runs the manifest.
  if (auto sent = dfu.control_out(DfuRequest::kDnload, static_cast<std::uint16_t>(blocks), {});
      !sent.ok())
    return fail(sent.error().kind, "final zero-length DNLOAD: " + sent.error().message);
  const auto manifest =
      poll_until(dfu, {DfuState::kDfuIdle, DfuState::kManifestWaitReset},
                 {DfuState::kManifestSync, DfuState::kManifest}, sleep, "the image at manifest");
  if (!manifest.ok()) return fail(manifest.error());
  return done();
}

Expected<std::vector<std::uint8_t>> dfu_upload(DfuControl& dfu, std::size_t length) {
  using Bytes = std::vector<std::uint8_t>;
  if (auto idle = dfu_make_idle(dfu); !idle.ok()) return fail<Bytes>(idle.error());
  Bytes out;
  for (std::size_t block = 0; out.size() < length; ++block) {
    if (block > 0xFFFF) break;
    const auto data = dfu.control_in(DfuRequest::kUpload, static_cast<std::uint16_t>(block),
                                     static_cast<std::uint16_t>(protocol::kDfuTransferSize));
    if (!data.ok())
      return fail<Bytes>(data.error().kind,
                         "UPLOAD " + block_text(block) + ": " + data.error().message);
    out.insert(out.end(), data.value().begin(), data.value().end());
    if (data.value().size() < protocol::kDfuTransferSize) break;  // a short block ends the upload
  }
  // Stopped before a short block: back to dfuIDLE.
  if (auto idle = dfu_make_idle(dfu); !idle.ok()) return fail<Bytes>(idle.error());
  if (out.size() > length) out.resize(length);
  return Expected<Bytes>::success(out);
}

// ---------------------------------------------------------------------------
// libusb

namespace {

/// A libusb context for the flasher's lifetime.
class UsbContext {
 public:
  UsbContext() { ok_ = libusb_init(&context_) == 0; }
  ~UsbContext() {
    if (ok_) libusb_exit(context_);
  }
  UsbContext(const UsbContext&) = delete;
  UsbContext& operator=(const UsbContext&) = delete;
  bool ok() const { return ok_; }
  libusb_context* get() const { return context_; }

 private:
  libusb_context* context_ = nullptr;
  bool ok_ = false;
};

/// An open device with one claimed interface; released and closed on destruction.
class ClaimedInterface {
 public:
  ClaimedInterface(libusb_device_handle* handle, int interface_number)
      : handle_(handle), interface_(interface_number) {}
  ~ClaimedInterface() {
    if (handle_ == nullptr) return;
    libusb_release_interface(handle_, interface_);
    libusb_close(handle_);
  }
  ClaimedInterface(const ClaimedInterface&) = delete;
  ClaimedInterface& operator=(const ClaimedInterface&) = delete;
  libusb_device_handle* handle() const { return handle_; }
  int interface_number() const { return interface_; }

 private:
  libusb_device_handle* handle_;
  int interface_;
};

class LibusbDfuControl final : public DfuControl {
 public:
  explicit LibusbDfuControl(const ClaimedInterface& claimed) : claimed_(claimed) {}

  Expected<Done> control_out(DfuRequest request, std::uint16_t value,
                             std::span<const std::uint8_t> data) override {
    const int rc = libusb_control_transfer(
        claimed_.handle(), protocol::kDfuRequestOut, static_cast<std::uint8_t>(request), value,
        static_cast<std::uint16_t>(claimed_.interface_number()),
        const_cast<unsigned char*>(data.data()), static_cast<std::uint16_t>(data.size()),
        kControlTimeoutMs);
    if (rc < 0)
      return fail(transfer_error_kind(rc),
                  std::string("USB control transfer failed: ") + libusb_strerror(rc));
    return done();
  }

  Expected<std::vector<std::uint8_t>> control_in(DfuRequest request, std::uint16_t value,
                                                 std::uint16_t length) override {
    std::vector<std::uint8_t> buffer(length);
    const int rc = libusb_control_transfer(claimed_.handle(), protocol::kDfuRequestIn,
                                           static_cast<std::uint8_t>(request), value,
                                           static_cast<std::uint16_t>(claimed_.interface_number()),
                                           buffer.data(), length, kControlTimeoutMs);
    if (rc < 0)
      return fail<std::vector<std::uint8_t>>(
          transfer_error_kind(rc),
          std::string("USB control transfer failed: ") + libusb_strerror(rc));
    buffer.resize(static_cast<std::size_t>(rc));
    return Expected<std::vector<std::uint8_t>>::success(buffer);
  }

 private:
  static ErrorKind transfer_error_kind(int rc) {
    if (rc == LIBUSB_ERROR_TIMEOUT) return ErrorKind::kTimeout;
    if (rc == LIBUSB_ERROR_PIPE) return ErrorKind::kRejected;  // stalled: request refused
    return ErrorKind::kGone;
  }
  const ClaimedInterface& claimed_;
};

/// The serial number string of an open device, empty if unreadable.
std::string serial_of(libusb_device_handle* handle, const libusb_device_descriptor& descriptor) {
  unsigned char text[128];
  if (descriptor.iSerialNumber == 0) return {};
  const int n =
      libusb_get_string_descriptor_ascii(handle, descriptor.iSerialNumber, text, sizeof text);
  return n > 0 ? std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(n))
               : std::string();
}

/// The DFU interface (runtime or DFU mode by `protocol`) of `device`, -1 if none.
int find_dfu_interface(libusb_device* device, std::uint8_t protocol) {
  libusb_config_descriptor* config = nullptr;
  if (libusb_get_active_config_descriptor(device, &config) != 0 &&
      libusb_get_config_descriptor(device, 0, &config) != 0)
    return -1;
  int found = -1;
  for (int i = 0; i < config->bNumInterfaces && found < 0; ++i) {
    const libusb_interface& interface = config->interface[i];
    for (int a = 0; a < interface.num_altsetting; ++a) {
      const libusb_interface_descriptor& alt = interface.altsetting[a];
      if (alt.bInterfaceClass == protocol::kDfuInterfaceClass &&
          alt.bInterfaceSubClass == protocol::kDfuInterfaceSubclass &&
          alt.bInterfaceProtocol == protocol) {
        found = alt.bInterfaceNumber;
        break;
      }
    }
  }
  libusb_free_config_descriptor(config);
  return found;
}

/// Opens the device with `product_id` and `serial` and claims its DFU interface.
Expected<std::unique_ptr<ClaimedInterface>> open_dfu_interface(UsbContext& usb,
                                                               std::uint16_t product_id,
                                                               const std::string& serial,
                                                               std::uint8_t protocol) {
  using Out = Expected<std::unique_ptr<ClaimedInterface>>;
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(usb.get(), &list);
  std::string problem = "not connected";
  std::unique_ptr<ClaimedInterface> claimed;
  for (ssize_t i = 0; i < count && !claimed; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(list[i], &descriptor) != 0 ||
        descriptor.idVendor != protocol::kUsbVendorId || descriptor.idProduct != product_id)
      continue;
    libusb_device_handle* handle = nullptr;
    if (const int rc = libusb_open(list[i], &handle); rc != 0) {
      problem = std::string("cannot open it (") + libusb_strerror(rc) +
                "): is the udev rule installed and are you in the plugdev group?";
      continue;
    }
    if (serial_of(handle, descriptor) != serial) {
      libusb_close(handle);
      continue;
    }
    const int interface_number = find_dfu_interface(list[i], protocol);
    if (interface_number < 0) {
      problem = "it has no DFU interface";
      libusb_close(handle);
      continue;
    }
    libusb_set_auto_detach_kernel_driver(handle, 1);
    if (const int rc = libusb_claim_interface(handle, interface_number); rc != 0) {
      problem = std::string("cannot claim its DFU interface (") + libusb_strerror(rc) + ")";
      libusb_close(handle);
      continue;
    }
    claimed = std::make_unique<ClaimedInterface>(handle, interface_number);
  }
  if (count >= 0) libusb_free_device_list(list, 1);  // an empty list is allocated too
  if (!claimed)
    return fail<std::unique_ptr<ClaimedInterface>>(
        ErrorKind::kNotFound,
        "controller " + serial + " (USB PID " + std::to_string(product_id) + "): " + problem);
  return Out::success(std::move(claimed));
}

/// Waits until a controller with `serial` shows up in `mode`.
Expected<Done> wait_for_mode(const std::string& serial, DeviceMode mode,
                             std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto found = find_controllers();
    if (found.ok())
      for (const auto& device : found.value())
        if (device.mode == mode && device.serial == serial) return done();
    if (std::chrono::steady_clock::now() >= deadline)
      return fail(ErrorKind::kTimeout, "controller " + serial + " did not appear in " +
                                           mode_name(mode) + " mode within " +
                                           std::to_string(timeout.count()) + " ms");
    std::this_thread::sleep_for(kEnumeratePoll);
  }
}

std::string version_text(std::uint8_t major, std::uint8_t minor, std::uint8_t patch) {
  return std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch);
}

void real_sleep(std::chrono::milliseconds ms) {
  std::this_thread::sleep_for(ms);
}

/// The flasher's clients: the device is expected to go away, so no reconnecting.
ClientOptions one_shot_client() {
  ClientOptions options;
  options.reconnect = false;
  return options;
}

}  // namespace

Expected<FlashReport> flash_controller(const FirmwareImage& image, const FlashOptions& options) {
  FlashReport report;
  const auto found = find_controllers();
  if (!found.ok()) return fail<FlashReport>(found.error());
  // The controller: named, or the only one in either mode.
  std::vector<FoundDevice> candidates;
  for (const auto& device : found.value())
    if (!options.serial || device.serial == *options.serial) candidates.push_back(device);
  if (candidates.empty())
    return fail<FlashReport>(ErrorKind::kNotFound, options.serial
                                                       ? "no controller with serial number " +
                                                             *options.serial + " is connected"
                                                       : std::string("no controller is connected"));
  if (candidates.size() > 1)
    return fail<FlashReport>(ErrorKind::kAmbiguous,
                             std::to_string(candidates.size()) +
                                 " controllers are connected and none was named: choose one with "
                                 "--device SERIAL\n" +
                                 describe_devices(candidates));
  const FoundDevice target = candidates.front();
  if (target.serial.empty())
    return fail<FlashReport>(ErrorKind::kAccess,
                             "cannot read the controller's serial number: " + target.problem);
  report.serial = target.serial;
  const std::string& serial = target.serial;

  UsbContext usb;
  if (!usb.ok()) return fail<FlashReport>(ErrorKind::kAccess, "libusb cannot start");

  if (target.mode == DeviceMode::kApplication) {
    // Which board and firmware is it? A protocol mismatch is no reason not to flash.
    auto client = ControllerClient::connect(hid_opener(serial), one_shot_client());
    if (client.ok()) {
      report.before = client.value()->info();
      if (report.before->board_id != image.header.board_id)
        return fail<FlashReport>(ErrorKind::kBadInput,
                                 image.source + ": refused, the image is for board " +
                                     std::to_string(image.header.board_id) + " but controller " +
                                     serial + " is board " +
                                     std::to_string(report.before->board_id));
      say(options, "controller " + serial + " runs firmware " +
                       version_text(report.before->firmware_major, report.before->firmware_minor,
                                    report.before->firmware_patch));
    } else if (client.error().kind == ErrorKind::kProtocolMismatch) {
      say(options, "controller " + serial + ": " + client.error().message + " (flashing it now)");
    } else {
      say(options, "controller " + serial + ": GetInfo failed (" + client.error().message +
                       "); detaching anyway");
    }
    // DFU_DETACH on the DFU runtime interface; WillDetach: the device resets itself.
    say(options, "detaching into the DFU bootloader");
    bool detached = false;
    {
      auto runtime = open_dfu_interface(usb, protocol::kUsbProductIdApplication, serial,
                                        protocol::kDfuProtocolRuntime);
      if (runtime.ok()) {
        LibusbDfuControl control(*runtime.value());
        const auto sent =
            control.control_out(DfuRequest::kDetach, protocol::kDfuDetachTimeoutMs, {});
        // The device may reset before the status stage: gone is fine.
        detached = sent.ok() || sent.error().kind == ErrorKind::kGone;
        if (!detached) say(options, "DFU_DETACH failed: " + sent.error().message);
      } else {
        say(options, runtime.error().message);
      }
    }
    if (!detached) {
      if (!client.ok())
        return fail<FlashReport>(ErrorKind::kGone,
                                 "cannot detach controller " + serial + " into its bootloader");
      say(options, "asking the application to enter its bootloader over HID instead");
      if (auto entered = client.value()->enter_bootloader(); !entered.ok())
        return fail<FlashReport>(entered.error());
    }
    if (client.ok()) client.value().reset();
    if (auto waited = wait_for_mode(serial, DeviceMode::kBootloader, options.enumerate_timeout);
        !waited.ok())
      return fail<FlashReport>(waited.error());
    say(options, "bootloader of " + serial + " is up");
  } else {
    say(options, "controller " + serial + " is already in DFU mode");
  }

  {
    auto claimed = open_dfu_interface(usb, protocol::kUsbProductIdBootloader, serial,
                                      protocol::kDfuProtocolDfuMode);
    if (!claimed.ok()) return fail<FlashReport>(claimed.error());
    LibusbDfuControl dfu(*claimed.value());
    const auto start = std::chrono::steady_clock::now();
    if (auto downloaded = dfu_download(dfu, image.bytes, options.progress, real_sleep);
        !downloaded.ok())
      return fail<FlashReport>(
          downloaded.error().kind,
          downloaded.error().message +
              "; the controller stays in DFU mode: run flutterscan flash again");
    report.download_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.kib_per_second = report.download_seconds > 0 ? static_cast<double>(image.bytes.size()) /
                                                              1024.0 / report.download_seconds
                                                        : 0;
    say(options, "downloaded and manifested; reading it back");
    const auto readback = dfu_upload(dfu, image.bytes.size());
    if (!readback.ok()) return fail<FlashReport>(readback.error());
    if (readback.value() != image.bytes) {
      std::size_t first = 0;
      while (first < readback.value().size() && readback.value()[first] == image.bytes[first])
        ++first;
      return fail<FlashReport>(ErrorKind::kRejected,
                               "read-back differs from the image at byte " + std::to_string(first) +
                                   " (" + std::to_string(readback.value().size()) + " bytes read)");
    }
    // Start the application: DFU_DETACH, then a bus reset (either starts it).
    dfu.control_out(DfuRequest::kDetach, protocol::kDfuDetachTimeoutMs, {});
    libusb_reset_device(claimed.value()->handle());
  }

  say(options, "waiting for the application");
  if (auto waited = wait_for_mode(serial, DeviceMode::kApplication, options.enumerate_timeout);
      !waited.ok())
    return fail<FlashReport>(waited.error());
  // Its HID node may appear a moment after the device: retry until the deadline.
  const auto connect_deadline = std::chrono::steady_clock::now() + options.enumerate_timeout;
  auto client = ControllerClient::connect(hid_opener(serial), one_shot_client());
  while (!client.ok() && client.error().kind != ErrorKind::kProtocolMismatch &&
         std::chrono::steady_clock::now() < connect_deadline) {
    std::this_thread::sleep_for(kEnumeratePoll);
    client = ControllerClient::connect(hid_opener(serial), one_shot_client());
  }
  if (!client.ok())
    return fail<FlashReport>(
        client.error().kind,
        "the new firmware of controller " + serial + " does not answer: " + client.error().message);
  report.after = client.value()->info();
  const auto& h = image.header;
  if (report.after.firmware_major != h.version_major ||
      report.after.firmware_minor != h.version_minor ||
      report.after.firmware_patch != h.version_patch || report.after.board_id != h.board_id)
    return fail<FlashReport>(
        ErrorKind::kRejected,
        "after flashing, controller " + serial + " reports firmware " +
            version_text(report.after.firmware_major, report.after.firmware_minor,
                         report.after.firmware_patch) +
            " on board " + std::to_string(report.after.board_id) + ", but the image is " +
            version_text(h.version_major, h.version_minor, h.version_patch) + " for board " +
            std::to_string(h.board_id));
  // The product application reports its stamped image CRC-32 as build_id; 0 means
  // a firmware that does not (then the UPLOAD read-back above is the CRC check).
  if (report.after.build_id != 0 && report.after.build_id != h.image_crc32) {
    char text[96];
    std::snprintf(text, sizeof text, "reports image CRC-32 %08X, the image has %08X",
                  report.after.build_id, h.image_crc32);
    return fail<FlashReport>(ErrorKind::kRejected,
                             "after flashing, controller " + serial + " " + text);
  }
  char crc_text[16];
  std::snprintf(crc_text, sizeof crc_text, "%08X", h.image_crc32);
  say(options, report.after.build_id != 0
                   ? std::string("the application confirms image CRC-32 ") + crc_text
                   : std::string("the application does not report its image CRC (build id 0); "
                                 "the read-back matched"));
  return Expected<FlashReport>::success(report);
}

}  // namespace flutterscan::device
