// SimUsbController's packet-level path (sim_usb_controller.hpp): endpoint 0 one
// transaction at a time, as the OTG_FS driver (port/stm32f4/src/otg_fs_device.cpp)
// plays a control transfer through the UsbDeviceController seam: the IN data
// stage is read from the core's buffer 64 bytes per packet, ending with a
// zero-length packet only where the seam asked for one; the OUT data stage goes
// into the core's buffer packet by packet (a packet beyond its room is cut) and
// is reported with on_ep0_out_complete() once the buffer is full or a packet
// shorter than 64 bytes ends it; the status stage completes the transfer
// (on_ep0_status_complete()). A SETUP always aborts the transfer in progress.
// Answers the seam forbids count as ep0_protocol_errors(), as in control_transfer().

#include <algorithm>

#include "flutterscan/firmware/sim/sim_usb_controller.hpp"

namespace flutterscan::firmware::sim {

void SimUsbController::setup_packet(std::span<const std::uint8_t, 8> setup_bytes) {
  ep0_stage_ = Ep0Stage::kIdle;
  if (device_ == nullptr) {
    ep0_stage_ = Ep0Stage::kStalled;
    return;
  }
  const usb::SetupPacket setup = usb::SetupPacket::parse(setup_bytes);
  ep0_setup_in_ = setup.is_in();
  ep0_setup_length_ = setup.length;
  ep0_answer_ = Ep0Answer::kNone;
  ep0_answers_ = 0;
  ep0_in_.clear();
  ep0_in_view_ = {};
  device_->on_setup(setup);
  enter_stage_after_answer();
}

void SimUsbController::enter_stage_after_answer() {
  if (ep0_answers_ != 1) ++ep0_protocol_errors_;
  switch (ep0_answer_) {
    case Ep0Answer::kNone:
    case Ep0Answer::kStall:
      ep0_stage_ = Ep0Stage::kStalled;
      return;
    case Ep0Answer::kTransmit:
      if (!ep0_setup_in_ || ep0_in_view_.size() > ep0_setup_length_) ++ep0_protocol_errors_;
      // A zero-length packet ends a data stage shorter than wLength that is a
      // multiple of the packet size, and only that one.
      if (ep0_zero_length_end_ != (ep0_in_view_.size() < ep0_setup_length_ &&
                                   ep0_in_view_.size() % usb::kEp0MaxPacket == 0))
        ++ep0_protocol_errors_;
      ep0_in_sent_ = 0;
      ep0_zero_length_pending_ = ep0_zero_length_end_;
      ep0_stage_ = Ep0Stage::kInData;
      return;
    case Ep0Answer::kStatus:
      if (ep0_setup_in_ && ep0_setup_length_ != 0) ++ep0_protocol_errors_;
      ep0_stage_ = Ep0Stage::kStatusIn;
      return;
    case Ep0Answer::kReceive:
      if (ep0_setup_in_ || ep0_out_buffer_.size() != ep0_setup_length_) ++ep0_protocol_errors_;
      ep0_out_received_ = 0;
      ep0_stage_ = Ep0Stage::kOutData;
      return;
  }
}

void SimUsbController::complete_status_stage() {
  ep0_stage_ = Ep0Stage::kIdle;
  ++ep0_completed_;
  device_->on_ep0_status_complete();
}

Ep0InPacket SimUsbController::ep0_in_packet() {
  Ep0InPacket packet;
  switch (ep0_stage_) {
    case Ep0Stage::kStalled:
      packet.handshake = Ep0Handshake::kStall;
      return packet;
    case Ep0Stage::kInData: {
      const std::size_t n =
          std::min<std::size_t>(usb::kEp0MaxPacket, ep0_in_view_.size() - ep0_in_sent_);
      // Read now, from the core's buffer, as the driver fills the FIFO.
      const auto bytes = ep0_in_view_.subspan(ep0_in_sent_, n);
      packet.data.assign(bytes.begin(), bytes.end());
      packet.handshake = Ep0Handshake::kAck;
      ep0_in_sent_ += n;
      if (n == 0) ep0_zero_length_pending_ = false;  // this was the zero-length packet
      if (ep0_in_sent_ == ep0_in_view_.size() &&
          (n < usb::kEp0MaxPacket || !ep0_zero_length_pending_))
        ep0_stage_ = Ep0Stage::kStatusOut;
      return packet;
    }
    case Ep0Stage::kStatusIn:
      packet.handshake = Ep0Handshake::kAck;  // the zero-length status packet
      complete_status_stage();
      return packet;
    case Ep0Stage::kIdle:
    case Ep0Stage::kOutData:
    case Ep0Stage::kStatusOut:
      break;
  }
  return packet;  // NAK
}

Ep0Handshake SimUsbController::ep0_out_packet(std::span<const std::uint8_t> packet) {
  if (packet.size() > usb::kEp0MaxPacket) return Ep0Handshake::kStall;  // not a transaction
  switch (ep0_stage_) {
    case Ep0Stage::kStalled:
      return Ep0Handshake::kStall;
    case Ep0Stage::kOutData: {
      const std::size_t n = std::min(packet.size(), ep0_out_buffer_.size() - ep0_out_received_);
      std::copy_n(packet.begin(), n,
                  ep0_out_buffer_.begin() + static_cast<std::ptrdiff_t>(ep0_out_received_));
      ep0_out_received_ += n;
      if (ep0_out_received_ < ep0_out_buffer_.size() && packet.size() == usb::kEp0MaxPacket)
        return Ep0Handshake::kAck;  // more to come
      ep0_answer_ = Ep0Answer::kNone;
      ep0_answers_ = 0;
      device_->on_ep0_out_complete(ep0_out_received_);
      if (ep0_answers_ != 1) ++ep0_protocol_errors_;
      if (ep0_answer_ == Ep0Answer::kStatus) {
        ep0_stage_ = Ep0Stage::kStatusIn;
      } else {
        if (ep0_answer_ != Ep0Answer::kStall) ++ep0_protocol_errors_;
        ep0_stage_ = Ep0Stage::kStalled;
      }
      return Ep0Handshake::kAck;
    }
    case Ep0Stage::kInData:
    case Ep0Stage::kStatusOut:
      if (!packet.empty()) {  // data where the status belongs: the device stalls
        ep0_stage_ = Ep0Stage::kStalled;
        return Ep0Handshake::kStall;
      }
      complete_status_stage();
      return Ep0Handshake::kAck;
    case Ep0Stage::kIdle:
    case Ep0Stage::kStatusIn:
      break;
  }
  return Ep0Handshake::kNak;
}

}  // namespace flutterscan::firmware::sim
