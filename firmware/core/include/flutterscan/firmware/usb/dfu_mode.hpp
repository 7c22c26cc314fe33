#pragma once
// The bootloader's DFU mode interface: plain USB DFU 1.1 (not DfuSe) over the
// Flash seam, as the USB contract in docs/protocol.md says.
//
// - DNLOAD block n (wValue = n from 0, at most wTransferSize bytes) goes right
//   after the bytes of blocks 0..n-1: region.load_address + bytes received so
//   far, so any transfer size the host picks (dfu-util -t 512) gives a
//   contiguous image. Blocks must come in order (otherwise dfuERROR,
//   errADDRESS); a block past the region: errADDRESS.
//   Each flash sector is erased when a write first reaches it; a sector that
//   starts below the application region (the bootloader's, the config page)
//   is never erased or written.
// - The data are written after the DFU_GETSTATUS that reports dfuDNBUSY with
//   a poll timeout estimated from the sector map (erase + program), i.e.
//   once that request's status stage is done; the next GETSTATUS says
//   dfuDNLOAD-IDLE (or dfuERROR: errERASE, errPROG, errVERIFY).
// - A zero-length DNLOAD ends the download (dfuMANIFEST-SYNC); GETSTATUS then
//   reports dfuMANIFEST and the image is checked with the common checker
//   (check_image: magic, header, board id, size, CRC-32 over exactly the bytes
//   downloaded) and what the bootloader's jump needs; failure: dfuERROR with
//   errFIRMWARE, the device stays in DFU mode. An image whose security_version
//   is below the board's security floor (security_floor.hpp: the newest
//   confirmed image's), however valid: dfuERROR with errVENDOR (anti-rollback).
//   Success (bitManifestationTolerant): the next GETSTATUS says dfuIDLE
//   and the application starts at the next USB reset or DFU_DETACH.
// - Blocks are programmed in whole words at aligned addresses
//   (kFlashProgramAlignment): a block's bytes after its last word boundary
//   wait for the next block, the last partial word for the manifest.
// - UPLOAD block n returns the region from the bytes already uploaded: up to the image
//   size of a valid-looking header, else the whole region; a short block
//   (fewer bytes than wLength) ends the upload (dfuIDLE).
// - ABORT returns to dfuIDLE from dfuIDLE and every download or upload state
//   that accepts requests; CLRSTATUS leaves dfuERROR.
// - DFU_DETACH in dfuIDLE starts the application if the region holds a valid image.
// - Once the application is to start (leave_requested(): after DFU_DETACH, or a
//   USB reset after a manifest), DNLOAD stalls (dfuERROR, errSTALLEDPKT):
//   nothing is written to the region the decision was made on before the
//   main loop resets the chip.
// - A request the state does not allow: STALL, dfuERROR with errSTALLEDPKT
//   (DFU 1.1 appendix A), except DFU_DETACH without a valid image (errFIRMWARE).
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/flash.hpp"
#include "flutterscan/firmware/security_floor.hpp"
#include "flutterscan/firmware/usb/dfu.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"
#include "flutterscan/firmware/usb/usb_function.hpp"

namespace flutterscan::firmware::usb {

/// Poll timeout reported for the manifest phase (the CRC-32 of at most 64 KiB).
inline constexpr std::uint32_t kDfuManifestPollMs = 50;

/// \brief The DFU mode interface of the bootloader.
class DfuMode final : public UsbFunction {
 public:
  /// \brief DFU mode writing `region` of `flash` (whose sectors `layout` lists),
  /// as interface `interface_number`, refusing images below `floor`. `flash`
  /// and `floor` must outlive it.
  DfuMode(Flash& flash, SecurityFloor& floor, const FlashLayout& layout, const AppRegion& region,
          std::uint8_t interface_number);

  DfuState state() const { return state_; }
  DfuStatus status() const { return status_; }
  /// \brief The application should start now (after a manifest and a USB reset, or DFU_DETACH).
  bool leave_requested() const { return leave_requested_; }
  /// \brief Whether the region holds an image the checker accepts.
  bool application_valid();
  /// \brief Bytes of the download so far (the end of the highest block written).
  std::uint32_t downloaded_bytes() const { return download_end_; }
  /// \brief The checker's verdict at the last manifest.
  ImageCheck last_manifest_check() const { return last_check_; }

  // UsbFunction ------------------------------------------------------------
  ControlReply control_request(const SetupPacket& setup, std::span<std::uint8_t> buffer) override;
  ControlReply control_out_data(const SetupPacket& setup,
                                std::span<const std::uint8_t> data) override;
  void control_complete(const SetupPacket& setup) override;
  void set_configured(bool configured) override { (void)configured; }
  void bus_reset() override;

 private:
  ControlReply dnload(const SetupPacket& setup);
  ControlReply upload(const SetupPacket& setup, std::span<std::uint8_t> buffer);
  ControlReply get_status(std::span<std::uint8_t> buffer);
  /// STALL and dfuERROR with `status`.
  ControlReply fail(DfuStatus status);
  void start_download();
  /// Estimated ms to erase and program the pending block.
  std::uint32_t block_poll_ms() const;
  /// Erases, programs and verifies the pending block: whole words only, the
  /// bytes after its last word boundary kept for the next block (or the manifest).
  void write_block();
  /// Programs `data` at `address` (word-aligned) and reads it back; false
  /// (dfuERROR: errPROG or errVERIFY) if either fails.
  bool program_verified(std::uint32_t address, std::span<const std::uint8_t> data);
  /// Programs the bytes kept after the last word boundary, padded with 0xFF.
  bool flush_partial_word();
  void manifest();
  std::uint32_t upload_size();

  Flash& flash_;
  SecurityFloor& floor_;
  FlashLayout layout_;
  AppRegion region_;
  std::uint8_t interface_number_;

  DfuState state_ = DfuState::kDfuIdle;
  DfuStatus status_ = DfuStatus::kOk;
  bool leave_requested_ = false;
  bool manifested_ = false;  ///< a download passed its manifest check (this session)
  ImageCheck last_check_ = ImageCheck::kOk;

  std::uint32_t next_block_ = 0;
  std::uint32_t download_end_ = 0;
  std::uint32_t erased_sectors_ = 0;  ///< bit s: sector s erased in this download
  bool block_pending_ = false;
  bool manifest_done_ = false;
  std::uint16_t pending_block_number_ = 0;
  std::uint32_t pending_offset_ = 0;  ///< where the pending block goes in the region
  std::uint32_t upload_offset_ = 0;   ///< bytes sent by this upload so far
  std::size_t pending_length_ = 0;
  std::array<std::uint8_t, kDfuTransferSize> block_{};
  /// Downloaded bytes after the last word boundary, not yet programmed (the
  /// flash programs whole words at aligned addresses, kFlashProgramAlignment).
  std::array<std::uint8_t, kFlashProgramAlignment> partial_word_{};
  std::size_t partial_length_ = 0;
};

}  // namespace flutterscan::firmware::usb
