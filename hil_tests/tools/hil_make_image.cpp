// hil_make_image: writes a stamped application image (common image header,
// CRC-32) like the ones the HIL tests flash: for a board id, with a version,
// of a size; --corrupt flips one payload byte after stamping (bad CRC).
//
//   hil_make_image OUT.bin [--board-id N] [--version 0.2.0] [--size BYTES] [--corrupt]

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/sim/sim_board.hpp"

int main(int argc, char** argv) {
  CLI::App app{"hil_make_image: a stamped application image for the HIL tests"};
  std::string out_path;
  std::string version = "0.2.0";
  unsigned board_id = flutterscan::kBoardIdStm32f405;
  std::size_t size = 24 * 1024;
  unsigned seed = 7;
  bool corrupt = false;
  app.add_option("out", out_path, "Where to write the .bin")->required();
  app.add_option("--board-id", board_id, "Board id in the header");
  app.add_option("--version", version, "MAJOR.MINOR.PATCH");
  app.add_option("--size", size, "Image size in bytes");
  app.add_option("--seed", seed, "Payload pattern");
  app.add_flag("--corrupt", corrupt, "Flip a payload byte after stamping (CRC mismatch)");
  CLI11_PARSE(app, argc, argv);
  int major = 0, minor = 0, patch = 0;
  if (std::sscanf(version.c_str(), "%d.%d.%d", &major, &minor, &patch) != 3) {
    std::cerr << "hil_make_image: --version " << version << ": expected MAJOR.MINOR.PATCH\n";
    return 2;
  }
  auto image = flutterscan::firmware::sim::make_application_image(
      static_cast<std::uint16_t>(board_id), static_cast<std::uint8_t>(major),
      static_cast<std::uint8_t>(minor), static_cast<std::uint8_t>(patch), size, seed);
  if (corrupt) image[image.size() / 2] ^= 0x5A;
  std::ofstream out(out_path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(image.data()),
            static_cast<std::streamsize>(image.size()));
  if (!out) {
    std::cerr << "hil_make_image: " << out_path << ": cannot be written\n";
    return 1;
  }
  return 0;
}
