#pragma once
// CRC-32 (zlib's): the one implementation in common/crc32.hpp, under the
// firmware namespace the core has always used.

#include "flutterscan/common/crc32.hpp"

namespace flutterscan::firmware {

using flutterscan::crc32;
using flutterscan::crc32_extend;

}  // namespace flutterscan::firmware
