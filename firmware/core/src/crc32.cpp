#include "crc32.hpp"

#include <zlib.h>

#include <algorithm>
#include <limits>

namespace fpp {

std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc) {
    // zlib's (already linked through libpng) takes at most a uInt a call.
    const auto* p = static_cast<const Bytef*>(data);
    uLong c = crc;
    while (size > 0) {
        const std::size_t n = std::min<std::size_t>(size, std::numeric_limits<uInt>::max());
        c = ::crc32(c, p, static_cast<uInt>(n));
        p += n;
        size -= n;
    }
    return static_cast<std::uint32_t>(c);
}

} // namespace fpp
