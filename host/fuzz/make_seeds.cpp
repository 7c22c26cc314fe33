// Writes the seed corpora of host/fuzz's targets (run once; the output is kept
// in the repository under host/fuzz/<target>/corpus/, beside the findings):
//   build/bin/make_host_fuzz_seeds host/fuzz docs/session-example.toml
// Each seed is a valid input of its target, as the target's input format says
// (the first byte or bytes pick a mode, see each *_fuzz.cpp), plus the inputs of
// issue 20's reproductions (e.g. optics.px_per_count = 99999999999).

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <tuple>
#include <vector>

#include "flutterscan/common/image_header.hpp"
#include "imaging/capture_descriptor.hpp"

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;
using namespace flutterscan;

fs::path root;

void put(const std::string& target, const std::string& name, const Bytes& bytes) {
  const fs::path dir = root / target / "corpus";
  fs::create_directories(dir);
  std::ofstream(dir / ("seed-" + name), std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

/// `mode` then `body` (built by size, not insert: GCC 12 warns falsely on the latter).
template <typename Body>
Bytes with_mode(std::uint8_t mode, const Body& body) {
  Bytes out(1 + body.size());
  out[0] = mode;
  std::copy(body.begin(), body.end(), out.begin() + 1);
  return out;
}

void le32(Bytes& out, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i)
    out[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}
void le16(Bytes& out, std::size_t at, std::uint16_t v) {
  out[at] = static_cast<std::uint8_t>(v);
  out[at + 1] = static_cast<std::uint8_t>(v >> 8);
}

void session_config_seeds(const std::string& example_path) {
  std::ifstream in(example_path);
  const std::string example{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  put("session_config", "example", Bytes(example.begin(), example.end()));
  put("session_config", "empty", {});
  const std::pair<const char*, const char*> cases[] = {
      {"px-per-count-typo", "[optics]\npx_per_count = 99999999999\n"},
      {"nominal-blur", "[optics]\nencoder = false\nnominal_blur_px = 1e15\n"},
      {"camera-size", "[camera]\nwidth = 1000000000\nheight = -1\n"},
      {"queue", "[processing]\nqueue_depth = 1000000000000000\nworkers = 3\n"},
      {"slot-time-wraps", "[controller]\nslot_time_us = 4294967396\n"},
      {"auto", "[controller]\ncode = \"auto\"\nprobe_frames = 6\n[optics]\nread_noise_e = 4\n"},
      {"crosstalk", "[optics]\ncrosstalk = [[1,0,0],[0,1,0],[0,0,1]]\nblack_level_dn = 1e9\n"},
      {"output", "[output]\ndisk_budget_mb = 1e15\n[results]\ntcp_port = 0\nserial = \"x\"\n"},
  };
  for (const auto& [name, text] : cases)
    put("session_config", name, Bytes(text, text + std::strlen(text)));
}

void descriptor_seeds() {
  auto code = LedCode::parse("1241241242142141241421241241241241421241241242142141", 3).value();
  int n = 0;
  for (const char* direction : {"+x", "-x", "+y", "-y"})
    for (int channels : {3, 1}) {
      imaging::CaptureModel m;
      m.code = code;
      m.blur_px = 6 + 4 * n;
      imaging::parse_direction(direction, m.direction);
      m.channels = channels;
      m.crosstalk = channels == 3
                        ? std::vector<double>{0.9, 0.08, 0.01, 0.1, 0.85, 0.12, 0.01, 0.07, 0.88}
                        : std::vector<double>{1, 1, 1};
      m.led_electrons = {400, 400, 400};
      m.ambient_electrons.assign(static_cast<std::size_t>(channels), 10.0);
      m.gain = 3;
      m.black_level = 64;
      m.bayer_rggb = channels == 3 && n % 4 == 2;
      put("capture_descriptor", "model-" + std::to_string(n),
          with_mode(static_cast<std::uint8_t>(n), imaging::to_descriptor(m).dump()));
      ++n;
    }
}

/// files_camera: byte 0 the frames and which one (files_camera_fuzz.cpp), then a
/// descriptor: a kept frame's as a session writes it, a bare one, a Bayer one, and
/// one per field the files camera reads and JSON type it must refuse there (each
/// ended `scan --camera files:` and `replay` with an uncaught exception once).
void files_camera_seeds() {
  auto code = LedCode::parse("1241241242142141241421241241241241421241241242142141", 3).value();
  imaging::CaptureModel m;
  m.code = code;
  m.blur_px = 20;
  m.crosstalk = {0.9, 0.08, 0.01, 0.1, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.led_electrons = {400, 400, 400};
  m.ambient_electrons = {10, 10, 10};
  m.gain = 3;
  m.black_level = 64;
  nlohmann::json kept = imaging::to_descriptor(m);
  kept["capture"] = {{"sequence", 12},
                     {"timestamp_ns", 400'000'000},
                     {"exposure_counter", 12},
                     {"truth", {"4006381333931", "FS-00020"}},
                     {"truth_in_view", {"4006381333931"}}};
  for (std::uint8_t mode = 0; mode < 8; ++mode)
    put("files_camera", "kept-" + std::to_string(mode), with_mode(mode, kept.dump()));
  const std::string bare = "{}";
  put("files_camera", "bare", with_mode(1, bare));
  const std::string bayer = R"({"bayer":"RGGB","bit_depth":10})";
  put("files_camera", "bayer", with_mode(1, bayer));
  const std::pair<const char*, nlohmann::json::json_pointer> fields[] = {
      {"bit-depth", nlohmann::json::json_pointer("/bit_depth")},
      {"capture", nlohmann::json::json_pointer("/capture")},
      {"sequence", nlohmann::json::json_pointer("/capture/sequence")},
      {"timestamp", nlohmann::json::json_pointer("/capture/timestamp_ns")},
      {"truth", nlohmann::json::json_pointer("/capture/truth")},
      {"truth-in-view", nlohmann::json::json_pointer("/capture/truth_in_view")}};
  const std::pair<const char*, nlohmann::json> values[] = {
      {"string", "x"}, {"null", nullptr}, {"array", {1}}, {"object", {{"a", 1}}}};
  std::uint8_t mode = 0;
  for (const auto& [field, pointer] : fields)
    for (const auto& [type, value] : values) {
      nlohmann::json wrong = kept;
      wrong[pointer] = value;
      put("files_camera", std::string(field) + "-" + type, with_mode(mode++ % 8, wrong.dump()));
    }
}

void frame_seeds() {
  int n = 0;
  for (int depth : {CV_8U, CV_16U})
    for (int channels : {1, 3})
      for (const char* ext : {".png", ".tiff"}) {
        cv::Mat mat(12, 20, CV_MAKETYPE(depth, channels));
        cv::randu(mat, 0, depth == CV_8U ? 255 : 4095);
        std::vector<std::uint8_t> encoded;
        cv::imencode(ext, mat, encoded);
        put("frame_decode", "file-" + std::to_string(n++) + ext, with_mode(0, encoded));
      }
  // Camera frames: format, width, height, bit depth, stride byte (< 200: packed), pixels.
  for (std::uint8_t format = 0; format < 9; ++format) {
    const std::uint8_t width = 8, height = 6;
    const int bytes_per_pixel[] = {1, 2, 3, 3, 6, 1, 2, 2, 1};
    Bytes seed{1,
               format,
               width,
               height,
               static_cast<std::uint8_t>(format == 1 || format == 4 || format == 6 ? 12 : 8),
               0};
    for (int i = 0; i < width * height * bytes_per_pixel[format]; ++i)
      seed.push_back(static_cast<std::uint8_t>(i * 37 + 11));
    put("frame_decode", "camera-" + std::to_string(format), seed);
  }
}

Bytes firmware(std::size_t payload) {
  Bytes image(512 + payload, 0);
  ImageHeader h{};
  h.magic = kImageMagic;
  h.header_version = kImageHeaderVersion;
  h.header_size = sizeof(ImageHeader);
  h.board_id = kStm32f405AppRegion.board_id;
  h.version_minor = 1;
  h.load_address = kStm32f405AppRegion.load_address;
  h.vector_table_offset = 512;
  std::memcpy(image.data(), &h, sizeof h);
  for (std::size_t i = 512; i < image.size(); ++i) image[i] = static_cast<std::uint8_t>(i * 13 + 5);
  stamp_image(image);
  return image;
}

std::string hex_line(std::uint8_t type, std::uint16_t address, const std::uint8_t* data,
                     std::size_t n) {
  char text[16];
  std::string line = ":";
  unsigned sum = static_cast<unsigned>(n) + (address >> 8) + (address & 0xFF) + type;
  std::snprintf(text, sizeof text, "%02X%04X%02X", static_cast<unsigned>(n), address, type);
  line += text;
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(text, sizeof text, "%02X", data[i]);
    line += text;
    sum += data[i];
  }
  std::snprintf(text, sizeof text, "%02X", (256 - (sum & 0xFF)) & 0xFF);
  return line + text + "\n";
}

void firmware_seeds() {
  const Bytes image = firmware(700);
  const std::uint32_t base = kStm32f405AppRegion.load_address;
  const Bytes bin = with_mode(0, image);
  put("firmware_image", "bin", bin);
  put("firmware_image", "bin-restamp", [&] {
    Bytes b = bin;
    b[0] = 4;
    b[40] ^= 1;
    return b;
  }());
  std::string hex;
  const std::uint8_t upper[2] = {static_cast<std::uint8_t>(base >> 24),
                                 static_cast<std::uint8_t>(base >> 16)};
  hex += hex_line(0x04, 0, upper, 2);
  for (std::size_t at = 0; at < image.size(); at += 16)
    hex += hex_line(0x00, static_cast<std::uint16_t>((base + at) & 0xFFFF), image.data() + at,
                    std::min<std::size_t>(16, image.size() - at));
  hex += ":00000001FF\n";
  put("firmware_image", "hex", with_mode(1, hex));
  // ELF32 ARM, one PT_LOAD segment at the load address.
  Bytes elf(52 + 32, 0);
  elf[0] = 0x7F, elf[1] = 'E', elf[2] = 'L', elf[3] = 'F', elf[4] = 1, elf[5] = 1, elf[6] = 1;
  le16(elf, 16, 2);
  le16(elf, 18, 40);
  le32(elf, 20, 1);
  le32(elf, 24, base + 513);
  le32(elf, 28, 52);
  le16(elf, 40, 52);
  le16(elf, 42, 32);
  le16(elf, 44, 1);
  le32(elf, 52, 1);
  le32(elf, 56, 84);
  le32(elf, 60, base);
  le32(elf, 64, base);
  le32(elf, 68, static_cast<std::uint32_t>(image.size()));
  le32(elf, 72, static_cast<std::uint32_t>(image.size()));
  const std::size_t headers = elf.size();
  elf.resize(headers + image.size());
  std::copy(image.begin(), image.end(), elf.begin() + static_cast<std::ptrdiff_t>(headers));
  put("firmware_image", "elf", with_mode(2, elf));
}

void device_seeds() {
  // Client: a GetInfo reply echoed (protocol major 1 in the first payload byte), then
  // replies to a few commands and an exposure event.
  Bytes client{0};  // (the device_client target: no mode byte; a byte kept for the format)
  auto reply = [&](std::uint8_t how, std::uint8_t length, std::uint8_t status,
                   std::initializer_list<std::uint8_t> payload) {
    client.push_back(how);
    Bytes report(64, 0);
    report[2] = length;
    report[3] = status;
    std::size_t i = 4;
    for (std::uint8_t b : payload) report[i++] = b;
    client.insert(client.end(), report.begin(), report.end());
  };
  reply(0x00, 28, 0, {1, 0});  // GetInfo: protocol major 1, 28 bytes
  for (std::uint8_t command : {0, 1, 3, 4, 11, 2, 5, 6}) {
    client.push_back(command);
    reply(0x00, 0, 0, {});
  }
  put("device_client", "client", client);
  Bytes event = client;
  event.push_back(11);
  event.push_back(0x04);  // one report, not echoed: an exposure event
  Bytes report(64, 0);
  report[0] = 0x80;
  report[2] = 32;
  event.insert(event.end(), report.begin(), report.end());
  put("device_client", "client-event", event);
  // DFU, in the order fuzz_dfu asks: GETSTATUS (a "how" byte 2, then its 6 bytes:
  // status, bwPollTimeout, state, string), transfer results (1: ok), the image size
  // (2049 bytes: 3 blocks) and the upload length (1500: one full block, one short).
  auto dfu_seed = [](std::uint8_t poll_high) {
    Bytes dfu{1};
    auto status = [&](std::uint8_t state) {
      for (std::uint8_t b : {std::uint8_t{2}, std::uint8_t{0}, std::uint8_t{10}, std::uint8_t{0},
                             poll_high, state, std::uint8_t{0}})
        dfu.push_back(b);
    };
    status(2);                                 // dfu_get_status: dfuIDLE
    status(2);                                 // dfu_make_idle
    dfu.push_back(0x00), dfu.push_back(0x08);  // image size 2049
    status(2);                                 // download: make_idle
    for (int block = 0; block < 3; ++block) {
      dfu.push_back(1);  // DNLOAD ok
      status(4);         // dfuDNBUSY
      status(5);         // dfuDNLOAD-IDLE
    }
    dfu.push_back(1);                          // the zero-length DNLOAD
    status(7);                                 // dfuMANIFEST
    status(2);                                 // dfuIDLE
    dfu.push_back(0xDC), dfu.push_back(0x05);  // upload 1500 bytes
    status(2);                                 // upload: make_idle
    dfu.push_back(2);                          // a full block
    for (int i = 0; i < 1024; ++i) dfu.push_back(static_cast<std::uint8_t>(i));
    dfu.push_back(1), dfu.push_back(0x10), dfu.push_back(0x00);  // a short block of 16
    for (int i = 0; i < 16; ++i) dfu.push_back(static_cast<std::uint8_t>(i));
    status(9);         // dfuUPLOAD-IDLE
    dfu.push_back(1);  // ABORT ok
    status(2);
    return dfu;
  };
  // Reports for the parsers: a length byte, then the report (GetInfo, GetStatus
  // with a refusal, an exposure event, a short one).
  Bytes reports{2};
  for (const auto& [command, length, status] : {std::tuple{0x01, 28, 0}, std::tuple{0x09, 0, 5},
                                                std::tuple{0x80, 32, 0}, std::tuple{0x02, 2, 0}}) {
    reports.push_back(64);
    Bytes r(64, 0);
    r[0] = static_cast<std::uint8_t>(command);
    r[2] = static_cast<std::uint8_t>(length);
    r[3] = static_cast<std::uint8_t>(status);
    for (std::size_t i = 4; i < 4 + static_cast<std::size_t>(length); ++i)
      r[i] = static_cast<std::uint8_t>(i);
    for (std::uint8_t b : r) reports.push_back(b);
  }
  put("device_reply", "reports", reports);
  put("device_reply", "dfu", dfu_seed(0));
  put("device_reply", "dfu-slow", dfu_seed(0xFF));  // bwPollTimeout 0xFF000A ms: 4.6 hours
}

void pipeline_seeds() {
  for (int i = 0; i < 8; ++i) {
    Bytes seed(200);
    for (std::size_t j = 0; j < seed.size(); ++j)
      seed[j] = static_cast<std::uint8_t>((j * 29 + static_cast<std::size_t>(i) * 71) % 200);
    put("pipeline", "model-" + std::to_string(i), seed);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_host_fuzz_seeds HOST_FUZZ_DIR SESSION_EXAMPLE_TOML\n");
    return 2;
  }
  root = argv[1];
  session_config_seeds(argv[2]);
  descriptor_seeds();
  files_camera_seeds();
  frame_seeds();
  firmware_seeds();
  device_seeds();
  pipeline_seeds();
  return 0;
}
