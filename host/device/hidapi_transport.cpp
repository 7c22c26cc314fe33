#include "device/hidapi_transport.hpp"

#include <hidapi.h>

#include <mutex>
#include <thread>

namespace flutterscan::device {

namespace {

/// hid_read_timeout's wait per call: short, because under umockdev it returns at
/// once (the emulated node always polls ready) and on hardware it blocks.
constexpr int kReadSliceMs = 2;
/// Sleep between empty reads (only matters when reads return at once).
constexpr auto kEmptyReadPause = std::chrono::microseconds(300);

std::string hid_error_text(hid_device* device) {
  const wchar_t* text = hid_error(device);
  if (text == nullptr) return "unknown hidapi error";
  std::string out;
  for (; *text != 0; ++text) out += *text < 128 ? static_cast<char>(*text) : '?';
  return out;
}

void ensure_hid_init() {
  static const int result = hid_init();
  (void)result;
}

}  // namespace

HidapiTransport::HidapiTransport(hid_device* device, std::string path, std::string serial)
    : device_(device), path_(std::move(path)), serial_(std::move(serial)) {}

HidapiTransport::~HidapiTransport() {
  close();
}

Expected<std::unique_ptr<Transport>> HidapiTransport::open(const std::string& path,
                                                           const std::string& serial) {
  ensure_hid_init();
  hid_device* device = hid_open_path(path.c_str());
  if (device == nullptr)
    return fail<std::unique_ptr<Transport>>(
        ErrorKind::kAccess, "cannot open controller " + serial + " at " + path + " (" +
                                hid_error_text(nullptr) +
                                "): is the udev rule installed and are you in the plugdev group?");
  return Expected<std::unique_ptr<Transport>>::success(
      std::unique_ptr<Transport>(new HidapiTransport(device, path, serial)));
}

Expected<Done> HidapiTransport::write_report(std::span<const std::uint8_t> report) {
  if (report.size() > protocol::kReportSize)
    return fail(ErrorKind::kBadInput, "report of " + std::to_string(report.size()) + " bytes");
  // No report IDs: hidapi wants a leading 0, then the 64 report bytes.
  std::array<unsigned char, protocol::kReportSize + 1> buffer{};
  std::copy(report.begin(), report.end(), buffer.begin() + 1);
  std::shared_lock lock(use_mutex_);
  if (closed_) return fail(ErrorKind::kGone, description() + " is closed");
  const int written = hid_write(device_, buffer.data(), buffer.size());
  if (written < 0)
    return fail(ErrorKind::kGone,
                description() + ": write failed (" + hid_error_text(device_) + ")");
  return done();
}

Expected<std::optional<Report>> HidapiTransport::read_report(std::chrono::milliseconds timeout) {
  using Out = Expected<std::optional<Report>>;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    Report report{};
    int read = 0;
    {
      std::shared_lock lock(use_mutex_);
      if (closed_)
        return fail<std::optional<Report>>(ErrorKind::kGone, description() + " is closed");
      read = hid_read_timeout(device_, report.data(), report.size(), kReadSliceMs);
      if (read < 0)
        return fail<std::optional<Report>>(
            ErrorKind::kGone, description() + ": read failed (" + hid_error_text(device_) + ")");
    }
    if (read > 0) return Out::success(report);  // short reports arrive zero-padded
    if (std::chrono::steady_clock::now() >= deadline) return Out::success(std::nullopt);
    std::this_thread::sleep_for(kEmptyReadPause);
  }
}

void HidapiTransport::close() {
  std::unique_lock lock(use_mutex_);
  if (closed_) return;
  closed_ = true;
  hid_close(device_);
}

std::string HidapiTransport::description() const {
  return "controller " + serial_ + " (" + path_ + ")";
}

}  // namespace flutterscan::device
