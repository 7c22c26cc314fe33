#pragma once
// Write protection of flash sector 0 (the bootloader) in the option bytes.

/// \brief Sets nWRP0 = 0 in the option bytes (RM0090 3.6.2 and 3.9.7: OPTKEYR
/// unlock, OPTCR with only nWRP0 cleared, OPTSTRT, wait for BSY, OPTLOCK) unless
/// it is already set: idempotent, a no-op on every boot after the first. True if
/// sector 0 is write-protected afterwards.
bool protect_bootloader_sector();
