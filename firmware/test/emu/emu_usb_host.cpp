#include "emu_usb_host.hpp"

#include <algorithm>
#include <cstring>

namespace flutterscan::firmware::emu {
namespace {

constexpr int kHidEndpoint = 1;

const char* name(OtgFs::Handshake h) {
  switch (h) {
    case OtgFs::Handshake::kAck:
      return "ACK";
    case OtgFs::Handshake::kNak:
      return "NAK";
    case OtgFs::Handshake::kStall:
      return "STALL";
    case OtgFs::Handshake::kNoDevice:
      return "no device on the bus";
  }
  return "?";
}

}  // namespace

std::string UsbHost::advance(std::uint64_t cycles) {
  const std::string out = chip_.run_for(cycles);
  return out == "ran" ? "" : "chip: " + out;
}

std::string UsbHost::poll_in() {
  std::vector<std::uint8_t> packet;
  const OtgFs::Handshake h = chip_.otg_fs().in(kHidEndpoint, &packet);
  if (h == OtgFs::Handshake::kNak) return "";
  if (h == OtgFs::Handshake::kNoDevice) {  // it left the bus (a reset): enumerate it again
    configured_ = false;
    return "";
  }
  if (h != OtgFs::Handshake::kAck) return std::string("EP1 IN: ") + name(h);
  if (packet.size() != 64) return "EP1 IN: a report of " + std::to_string(packet.size()) + " bytes";
  Report r{};
  std::copy(packet.begin(), packet.end(), r.begin());
  (r[0] >= 0x80 ? events_ : replies_).push_back(r);
  return "";
}

std::string UsbHost::run_for(std::uint64_t cycles) {
  const std::uint64_t end = chip_.cycles() + cycles;
  while (chip_.cycles() < end) {
    if (configured_ && chip_.cycles() >= next_frame_) {
      if (const std::string e = poll_in(); !e.empty()) return e;
      next_frame_ = chip_.cycles() + kFrame;
    }
    const std::uint64_t until = configured_ ? std::min(end, next_frame_) : end;
    if (const std::string e = advance(until - chip_.cycles()); !e.empty()) return e;
  }
  return "";
}

std::string UsbHost::transact(const char* what,
                              const std::function<OtgFs::Handshake()>& transaction,
                              bool status_of_set_address) {
  const std::uint64_t deadline = chip_.cycles() + kTimeout;
  while (chip_.cycles() < deadline) {
    // A device that has not taken the host's address does not answer it. The
    // status stage of SET_ADDRESS is the exception: RM0090 34.17.5 has the
    // application write DCFG.DAD before it, at the SETUP.
    if (chip_.otg_fs().address() == address_ || status_of_set_address) {
      const OtgFs::Handshake h = transaction();
      if (h == OtgFs::Handshake::kAck) return "";
      if (h != OtgFs::Handshake::kNak) return std::string(what) + ": " + name(h);
    }
    if (const std::string e = advance(kRetry); !e.empty()) return e;
  }
  return std::string(what) + ": no answer within 50 ms at address " + std::to_string(address_);
}

std::string UsbHost::control_in(const Setup& setup, std::vector<std::uint8_t>* data) {
  OtgFs& otg = chip_.otg_fs();
  if (std::string e = transact("SETUP", [&] { return otg.setup(setup); }); !e.empty()) return e;
  const std::size_t length = setup[6] | setup[7] << 8;
  data->clear();
  // Data stage: IN packets until wLength or a short packet (USB 2.0 8.5.3.2).
  for (;;) {
    std::vector<std::uint8_t> packet;
    if (std::string e = transact("control IN", [&] { return otg.in(0, &packet); }); !e.empty())
      return e;
    data->insert(data->end(), packet.begin(), packet.end());
    if (packet.size() < 64 || data->size() >= length) break;
  }
  // Status stage: a zero-length OUT.
  return transact("status OUT", [&] { return otg.out(0, {}); });
}

std::string UsbHost::control_out(const Setup& setup, std::span<const std::uint8_t> data) {
  OtgFs& otg = chip_.otg_fs();
  if (std::string e = transact("SETUP", [&] { return otg.setup(setup); }); !e.empty()) return e;
  // Data stage: OUT packets of up to 64 bytes (USB 2.0 8.5.3.1), then a zero-length IN.
  for (std::size_t at = 0; at < data.size(); at += 64) {
    const auto packet = data.subspan(at, std::min<std::size_t>(64, data.size() - at));
    if (std::string e = transact("control OUT", [&] { return otg.out(0, packet); }); !e.empty())
      return e;
  }
  std::vector<std::uint8_t> packet;
  if (std::string e = transact("status IN", [&] { return otg.in(0, &packet); }); !e.empty())
    return e;
  return packet.empty() ? "" : "status IN: a packet of " + std::to_string(packet.size()) + " bytes";
}

std::string UsbHost::control_no_data(const Setup& setup) {
  OtgFs& otg = chip_.otg_fs();
  if (std::string e = transact("SETUP", [&] { return otg.setup(setup); }); !e.empty()) return e;
  std::vector<std::uint8_t> packet;
  const bool set_address = setup[0] == 0x00 && setup[1] == 5;
  if (std::string e = transact(
          "status IN", [&] { return otg.in(0, &packet); }, set_address);
      !e.empty())
    return e;
  return packet.empty() ? "" : "status IN: a packet of " + std::to_string(packet.size()) + " bytes";
}

std::string UsbHost::enumerate(std::uint8_t address) {
  const std::uint64_t deadline = chip_.cycles() + kTimeout;
  while (!chip_.otg_fs().attached()) {
    if (chip_.cycles() >= deadline) return "no pull-up within 50 ms";
    if (std::string e = advance(kRetry); !e.empty()) return e;
  }
  // Reset (USB 2.0 7.1.7.5: at least 10 ms), then the core's end of enumeration.
  address_ = 0;
  configured_ = false;
  chip_.otg_fs().bus_reset();
  if (std::string e = advance(10 * kFrame); !e.empty()) return e;
  chip_.otg_fs().enumeration_done();
  if (std::string e = advance(kFrame); !e.empty()) return e;
  std::vector<std::uint8_t> d;
  if (std::string e = control_in({0x80, 6, 0, 1, 0, 0, 64, 0}, &d); !e.empty())
    return "GET_DESCRIPTOR(device): " + e;
  if (d.size() != 18 || d[0] != 18 || d[1] != 1)
    return "GET_DESCRIPTOR(device): not a device descriptor";
  device_descriptor_ = d;
  if (std::string e = control_no_data({0x00, 5, address, 0, 0, 0, 0, 0}); !e.empty())
    return "SET_ADDRESS: " + e;
  address_ = address;  // USB 2.0 9.2.6.3: the device has 2 ms to take it
  if (std::string e = advance(2 * kFrame); !e.empty()) return e;
  if (chip_.otg_fs().address() != address)
    return "SET_ADDRESS: DCFG.DAD is " + std::to_string(chip_.otg_fs().address());
  if (std::string e = control_in({0x80, 6, 0, 2, 0, 0, 0xFF, 0}, &d); !e.empty())
    return "GET_DESCRIPTOR(configuration): " + e;
  if (d.size() < 9 || d[1] != 2 || static_cast<std::size_t>(d[2] | d[3] << 8) != d.size())
    return "GET_DESCRIPTOR(configuration): not the whole configuration";
  if (std::string e = control_no_data({0x00, 9, 1, 0, 0, 0, 0, 0}); !e.empty())
    return "SET_CONFIGURATION: " + e;
  configured_ = true;
  next_frame_ = chip_.cycles();
  return "";
}

std::string UsbHost::request(const Report& report, Report* reply) {
  OtgFs& otg = chip_.otg_fs();
  if (std::string e = transact("EP1 OUT", [&] { return otg.out(kHidEndpoint, report); });
      !e.empty())
    return e;
  const std::uint64_t deadline = chip_.cycles() + kTimeout;
  while (chip_.cycles() < deadline) {
    for (auto it = replies_.begin(); it != replies_.end(); ++it)
      if ((*it)[0] == report[0] && (*it)[1] == report[1]) {
        *reply = *it;
        replies_.erase(it);
        return "";
      }
    if (std::string e = run_for(kRetry); !e.empty()) return e;
  }
  return "no reply to command " + std::to_string(report[0]) + " within 50 ms";
}

}  // namespace flutterscan::firmware::emu
