// libFuzzer target: a firmware image file (.bin, Intel .hex, .elf) through the
// host's parser (flatten_image) and check (check_firmware_image), as `flutterscan
// flash` reads one, then, if accepted, through the DFU download to a bootloader
// that records what it is sent (host/device/firmware_image.hpp, dfu_flasher.hpp).
//
// Input: byte 0 picks the format (bits 0-1: bin, hex, elf, elf) and whether the
// flattened image is re-stamped (bit 2: header CRCs made right, so the layout and
// board checks behind the CRCs get fuzzed too); the rest is the file, for the
// product board's region.
// Oracles: a refusal is kBadInput with a message; an accepted image passes the
// bootloader's own check_image and is what the bootloader receives, byte for
// byte; so an image refused by check_image never reaches the download (the host
// may refuse more: it also checks the header's load address).

#include <vector>

#include "device/dfu_flasher.hpp"
#include "device/firmware_image.hpp"
#include "fuzz_support.hpp"

using namespace flutterscan;
using namespace flutterscan::device;

namespace {

/// A DFU bootloader that accepts every block in order and keeps them.
class RecordingBootloader final : public DfuControl {
 public:
  std::vector<std::uint8_t> received;
  DfuState state = DfuState::kDfuIdle;
  bool finished = false;

  Expected<Done> control_out(DfuRequest request, std::uint16_t value,
                             std::span<const std::uint8_t> data) override {
    if (request == DfuRequest::kDnload) {
      if (data.empty()) {
        finished = true;
        state = DfuState::kManifestSync;
      } else {
        FUZZ_CHECK(value * protocol::kDfuTransferSize == received.size(), "block out of order");
        received.insert(received.end(), data.begin(), data.end());
        state = DfuState::kDnloadSync;
      }
    } else if (request == DfuRequest::kClrStatus || request == DfuRequest::kAbort) {
      state = DfuState::kDfuIdle;
    }
    return done();
  }

  Expected<std::vector<std::uint8_t>> control_in(DfuRequest request, std::uint16_t,
                                                 std::uint16_t) override {
    if (request != DfuRequest::kGetStatus)
      return fail<std::vector<std::uint8_t>>(ErrorKind::kBadReply, "not a bootloader for that");
    if (state == DfuState::kDnloadSync) state = DfuState::kDnloadIdle;
    if (state == DfuState::kManifestSync) state = DfuState::kDfuIdle;
    return Expected<std::vector<std::uint8_t>>::success(
        std::vector<std::uint8_t>{0, 0, 0, 0, static_cast<std::uint8_t>(state), 0});
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 512 * 1024) return 0;
  fuzz::Bytes in(data, size);
  const std::uint8_t mode = in.u8();
  const std::vector<std::uint8_t> file = in.rest();
  static constexpr ImageFormat kFormats[] = {ImageFormat::kBinary, ImageFormat::kIntelHex,
                                             ImageFormat::kElf, ImageFormat::kElf};
  const ImageFormat format = kFormats[mode & 3];
  const auto region = app_region_for_board(kStm32f405AppRegion.board_id);
  FUZZ_CHECK(region.has_value(), "the product board has no region");

  auto flat = flatten_image(file, format, *region, "fuzz");
  if (!flat.ok()) {
    fuzz::trace("file refused: " + flat.error().message);
    FUZZ_CHECK(flat.error().kind == ErrorKind::kBadInput && !flat.error().message.empty(),
               "a refused file must be bad input with a message: " + flat.error().message);
    return 0;
  }
  std::vector<std::uint8_t> bytes = flat.value();
  if ((mode & 4) != 0) stamp_image(bytes);
  const ImageCheck verdict = check_image(bytes, region->board_id, region->max_size);
  auto checked = check_firmware_image(bytes, *region, "fuzz");
  if (!checked.ok()) {
    fuzz::trace("image refused: " + checked.error().message);
    FUZZ_CHECK(checked.error().kind == ErrorKind::kBadInput && !checked.error().message.empty(),
               "a refused image must be bad input with a message");
    // The host may refuse more than the bootloader does (it also checks the header's
    // load address against the region), never less: see the accepted branch.
    return 0;  // refused: nothing goes to a device
  }
  const FirmwareImage& image = checked.value();
  FUZZ_CHECK(verdict == ImageCheck::kOk,
             "the host accepted an image the bootloader refuses: " + image_check_text(verdict));
  FUZZ_CHECK(check_image(image.bytes, region->board_id, region->max_size) == ImageCheck::kOk,
             "the image to be flashed does not pass check_image");
  FUZZ_CHECK(image.bytes.size() <= region->max_size, "image larger than the region");
  RecordingBootloader bootloader;
  const auto downloaded =
      dfu_download(bootloader, image.bytes, nullptr, [](std::chrono::milliseconds) {});
  fuzz::trace("image accepted and downloaded");
  FUZZ_CHECK(downloaded.ok(),
             "download to a good bootloader failed: " + downloaded.error().message);
  FUZZ_CHECK(bootloader.finished && bootloader.received == image.bytes,
             "the bootloader did not receive the checked image byte for byte");
  return 0;
}
