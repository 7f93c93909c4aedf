#pragma once
// CRC-32 of IEEE 802.3 (reflected polynomial 0xEDB88320, initial value and
// final XOR 0xFFFFFFFF; crc32("123456789") is 0xCBF43926), computed by
// zlib's crc32(). Used by the coefficient table file (.fpt).

#include <cstddef>
#include <cstdint>

namespace fpp {

// CRC of `size` bytes at `data`. Pass a previous result as `crc` to continue a
// running CRC over several pieces: crc32(b, nb, crc32(a, na)) == crc32(a + b).
std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc = 0);

} // namespace fpp
