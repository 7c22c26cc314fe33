#include "flutterscan/firmware/usb/dfu_mode.hpp"

#include <algorithm>

#include "flutterscan/firmware/boot_decision.hpp"

namespace flutterscan::firmware::usb {

namespace {

bool is_request(const SetupPacket& setup, std::uint8_t request_type) {
  return setup.request_type == request_type;
}

}  // namespace

DfuMode::DfuMode(Flash& flash, SecurityFloor& floor, const FlashLayout& layout,
                 const AppRegion& region, std::uint8_t interface_number)
    : flash_(flash),
      floor_(floor),
      layout_(layout),
      region_(region),
      interface_number_(interface_number) {}

bool DfuMode::application_valid() {
  const auto image = flash_.read(region_.load_address, region_.max_size);
  return check_boot_image(image, region_, floor_.floor()) == BootImageCheck::kOk;
}

ControlReply DfuMode::fail(DfuStatus status) {
  state_ = DfuState::kError;
  status_ = status;
  block_pending_ = false;
  return ControlReply::stall();
}

// ---------------------------------------------------------------------------
// Requests

ControlReply DfuMode::control_request(const SetupPacket& setup, std::span<std::uint8_t> buffer) {
  if (setup.index != interface_number_) return ControlReply::stall();
  if (state_ == DfuState::kDnBusy || state_ == DfuState::kManifest)
    return fail(DfuStatus::kErrStalledPacket);  // the host must wait bwPollTimeout
  switch (static_cast<DfuRequest>(setup.request)) {
    case DfuRequest::kDnload:
      // Once the application is to start, the region stays as it was checked:
      // the main loop resets only after this USB poll, which may hold more
      // requests (fuzz finding, firmware/fuzz/crashes/dfu-download-after-detach).
      if (!is_request(setup, kDfuRequestOut) || leave_requested_) break;
      return dnload(setup);
    case DfuRequest::kUpload:
      if (!is_request(setup, kDfuRequestIn)) break;
      return upload(setup, buffer);
    case DfuRequest::kGetStatus:
      if (!is_request(setup, kDfuRequestIn) || setup.value != 0 || setup.length == 0) break;
      return get_status(buffer);
    case DfuRequest::kGetState:
      if (!is_request(setup, kDfuRequestIn) || setup.value != 0 || setup.length == 0) break;
      buffer[0] = static_cast<std::uint8_t>(state_);
      return ControlReply::send(1);
    case DfuRequest::kClrStatus:
      if (!is_request(setup, kDfuRequestOut) || setup.length != 0 || state_ != DfuState::kError)
        break;
      state_ = DfuState::kDfuIdle;
      status_ = DfuStatus::kOk;
      return ControlReply::status();
    case DfuRequest::kAbort:
      if (!is_request(setup, kDfuRequestOut) || setup.length != 0) break;
      switch (state_) {
        case DfuState::kDfuIdle:
        case DfuState::kDnloadSync:
        case DfuState::kDnloadIdle:
        case DfuState::kManifestSync:
        case DfuState::kUploadIdle:
          state_ = DfuState::kDfuIdle;
          status_ = DfuStatus::kOk;
          block_pending_ = false;
          return ControlReply::status();
        default:
          break;
      }
      break;
    case DfuRequest::kDetach:
      if (!is_request(setup, kDfuRequestOut) || setup.length != 0 || state_ != DfuState::kDfuIdle)
        break;
      if (!application_valid()) return fail(DfuStatus::kErrFirmware);
      return ControlReply::status();  // leaves in control_complete
  }
  return fail(DfuStatus::kErrStalledPacket);
}

ControlReply DfuMode::dnload(const SetupPacket& setup) {
  if (setup.length > kDfuTransferSize) return fail(DfuStatus::kErrStalledPacket);
  if (state_ == DfuState::kDfuIdle) {
    if (setup.length == 0) return fail(DfuStatus::kErrStalledPacket);
    start_download();
    return ControlReply::receive();
  }
  if (state_ == DfuState::kDnloadIdle) {
    if (setup.length != 0) return ControlReply::receive();
    state_ = DfuState::kManifestSync;  // the download is complete
    manifest_done_ = false;
    return ControlReply::status();
  }
  return fail(DfuStatus::kErrStalledPacket);
}

void DfuMode::start_download() {
  next_block_ = 0;
  download_end_ = 0;
  pending_offset_ = 0;
  erased_sectors_ = 0;
  block_pending_ = false;
  partial_length_ = 0;
  manifest_done_ = false;
  manifested_ = false;
}

ControlReply DfuMode::control_out_data(const SetupPacket& setup,
                                       std::span<const std::uint8_t> data) {
  if (setup.request != static_cast<std::uint8_t>(DfuRequest::kDnload) || data.empty() ||
      data.size() > block_.size())
    return ControlReply::stall();
  // The data are acknowledged either way; a bad block shows in the next GETSTATUS.
  // A block goes right after the bytes received so far, whatever transfer size
  // the host chose (dfu-util -t 512: 512-byte blocks; block x 1024 left gaps).
  const std::uint64_t end = static_cast<std::uint64_t>(download_end_) + data.size();
  if (setup.value != next_block_ || end > region_.max_size) {
    state_ = DfuState::kError;
    status_ = DfuStatus::kErrAddress;
    block_pending_ = false;
    return ControlReply::status();
  }
  std::copy(data.begin(), data.end(), block_.begin());
  pending_block_number_ = setup.value;
  pending_offset_ = download_end_;
  pending_length_ = data.size();
  block_pending_ = true;
  state_ = DfuState::kDnloadSync;
  return ControlReply::status();
}

ControlReply DfuMode::get_status(std::span<std::uint8_t> buffer) {
  switch (state_) {
    case DfuState::kDnloadSync:
      if (block_pending_) {
        state_ = DfuState::kDnBusy;  // written when this request's status stage is done
        write_dfu_status(buffer, DfuStatus::kOk, block_poll_ms(), state_);
      } else {
        state_ = DfuState::kDnloadIdle;
        write_dfu_status(buffer, DfuStatus::kOk, 0, state_);
      }
      break;
    case DfuState::kManifestSync:
      if (!manifest_done_) {
        state_ = DfuState::kManifest;  // checked when this request's status stage is done
        write_dfu_status(buffer, DfuStatus::kOk, kDfuManifestPollMs, state_);
      } else {
        state_ = DfuState::kDfuIdle;  // manifestation tolerant
        manifested_ = true;
        write_dfu_status(buffer, DfuStatus::kOk, 0, state_);
      }
      break;
    default:
      write_dfu_status(buffer, status_, 0, state_);
      break;
  }
  return ControlReply::send(kDfuStatusSize);
}

ControlReply DfuMode::upload(const SetupPacket& setup, std::span<std::uint8_t> buffer) {
  if ((state_ != DfuState::kDfuIdle && state_ != DfuState::kUploadIdle) || setup.length == 0 ||
      setup.length > kDfuTransferSize || buffer.size() < setup.length)
    return fail(DfuStatus::kErrStalledPacket);
  if (state_ == DfuState::kDfuIdle) upload_offset_ = 0;  // a new upload
  const std::uint32_t size = upload_size();
  // Like a download: from the bytes sent so far, whatever the transfer size.
  const std::uint64_t offset = upload_offset_;
  const std::size_t n =
      offset < size ? std::min<std::size_t>(setup.length, size - static_cast<std::uint32_t>(offset))
                    : 0;
  if (n != 0) {
    const auto bytes = flash_.read(region_.load_address + static_cast<std::uint32_t>(offset), n);
    if (bytes.size() != n) return fail(DfuStatus::kErrAddress);
    std::copy(bytes.begin(), bytes.end(), buffer.begin());
  }
  upload_offset_ += static_cast<std::uint32_t>(n);
  state_ = n < setup.length ? DfuState::kDfuIdle : DfuState::kUploadIdle;
  return ControlReply::send(n);
}

std::uint32_t DfuMode::upload_size() {
  const auto bytes = flash_.read(region_.load_address, sizeof(ImageHeader));
  if (bytes.size() != sizeof(ImageHeader)) return region_.max_size;
  const ImageHeader h = read_image_header(bytes);
  if (h.magic == kImageMagic && h.header_crc32 == image_header_crc(h) &&
      h.image_size >= sizeof(ImageHeader) && h.image_size <= region_.max_size)
    return h.image_size;
  return region_.max_size;  // no image: the whole region, to see what is there
}

void DfuMode::control_complete(const SetupPacket& setup) {
  switch (static_cast<DfuRequest>(setup.request)) {
    case DfuRequest::kGetStatus:
      if (state_ == DfuState::kDnBusy)
        write_block();
      else if (state_ == DfuState::kManifest)
        manifest();
      break;
    case DfuRequest::kDetach:
      if (state_ == DfuState::kDfuIdle) leave_requested_ = true;
      break;
    default:
      break;
  }
}

void DfuMode::bus_reset() {
  if (manifested_ && state_ == DfuState::kDfuIdle) {
    leave_requested_ = true;
    return;
  }
  // A reset in the middle of a transfer abandons it; DFU mode stays.
  state_ = DfuState::kDfuIdle;
  status_ = DfuStatus::kOk;
  block_pending_ = false;
}

// ---------------------------------------------------------------------------
// Flash work

std::uint32_t DfuMode::block_poll_ms() const {
  const std::uint32_t address = region_.load_address + pending_offset_;
  std::uint32_t ms =
      layout_.program_ms_per_kib * static_cast<std::uint32_t>((pending_length_ + 1023) / 1024);
  for (std::uint32_t a = address; a < address + pending_length_;) {
    const int s = layout_.sector_of(a);
    if (s < 0) break;
    const FlashSector& sector = layout_.sectors[static_cast<std::size_t>(s)];
    if ((erased_sectors_ & (1u << s)) == 0) ms += sector.erase_ms;
    a = sector.base + sector.size;
  }
  return ms;
}

void DfuMode::write_block() {
  const std::uint32_t offset = pending_offset_;
  const std::uint32_t address = region_.load_address + offset;
  const auto data = std::span<const std::uint8_t>(block_).first(pending_length_);
  block_pending_ = false;
  for (std::uint32_t a = address; a < address + data.size();) {
    const int s = layout_.sector_of(a);
    if (s < 0 || s >= 32) {
      fail(DfuStatus::kErrAddress);
      return;
    }
    const FlashSector& sector = layout_.sectors[static_cast<std::size_t>(s)];
    // Never a sector reaching below the application region (bootloader, config page).
    if (sector.base < region_.load_address) {
      fail(DfuStatus::kErrAddress);
      return;
    }
    if ((erased_sectors_ & (1u << s)) == 0) {
      if (flash_.erase_sector(s) != FlashResult::kOk) {
        fail(DfuStatus::kErrErase);
        return;
      }
      erased_sectors_ |= 1u << s;
    }
    a = sector.base + sector.size;
  }
  // Whole words at aligned addresses only, whatever the transfer size (dfu-util
  // -t 1022 starts its second block at an unaligned address): first complete
  // the word the last block left partial, then every whole word of this one;
  // its last bytes wait for the next block, or for the manifest.
  std::uint32_t word_address = address - static_cast<std::uint32_t>(partial_length_);
  std::size_t used = 0;
  if (partial_length_ > 0) {
    used = std::min(partial_word_.size() - partial_length_, data.size());
    std::copy_n(data.begin(), used, partial_word_.begin() + partial_length_);
    partial_length_ += used;
    if (partial_length_ == partial_word_.size()) {
      if (!program_verified(word_address, partial_word_)) return;
      word_address += kFlashProgramAlignment;
      partial_length_ = 0;
    }
  }
  const std::size_t rest = data.size() - used;
  const std::size_t whole = rest - rest % kFlashProgramAlignment;
  if (whole > 0 && !program_verified(word_address, data.subspan(used, whole))) return;
  if (whole < rest) {
    partial_length_ = rest - whole;
    std::copy_n(data.begin() + static_cast<std::ptrdiff_t>(used + whole), partial_length_,
                partial_word_.begin());
  }
  download_end_ = offset + static_cast<std::uint32_t>(data.size());
  ++next_block_;
  state_ = DfuState::kDnloadSync;
}

bool DfuMode::program_verified(std::uint32_t address, std::span<const std::uint8_t> data) {
  if (flash_.program(address, data) != FlashResult::kOk) {
    fail(DfuStatus::kErrProg);
    return false;
  }
  const auto written = flash_.read(address, data.size());
  if (written.size() != data.size() || !std::equal(data.begin(), data.end(), written.begin())) {
    fail(DfuStatus::kErrVerify);
    return false;
  }
  return true;
}

bool DfuMode::flush_partial_word() {
  if (partial_length_ == 0) return true;
  const std::uint32_t address =
      region_.load_address + download_end_ - static_cast<std::uint32_t>(partial_length_);
  const std::size_t length = partial_length_;
  partial_length_ = 0;
  return program_verified(address, std::span<const std::uint8_t>(partial_word_).first(length));
}

void DfuMode::manifest() {
  if (!flush_partial_word()) return;
  const auto image = flash_.read(region_.load_address, download_end_);
  last_check_ = check_image(image, region_.board_id, region_.max_size);
  // Also what the bootloader's jump needs (load address, vector table, SP, PC):
  // an image the bootloader would not start is refused here, not after a reset.
  if (last_check_ != ImageCheck::kOk) {
    fail(DfuStatus::kErrFirmware);
    return;
  }
  const BootImageCheck boot = check_boot_image(image, region_, floor_.floor());
  if (boot != BootImageCheck::kOk) {
    fail(boot == BootImageCheck::kRolledBack ? DfuStatus::kErrVendor : DfuStatus::kErrFirmware);
    return;
  }
  manifest_done_ = true;
  state_ = DfuState::kManifestSync;
}

}  // namespace flutterscan::firmware::usb
