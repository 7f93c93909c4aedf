#pragma once
// FNV-1a 64 of a byte string: the fingerprint of a file's bytes (a
// calibration file's in a table's calibration_hash, a table's in the
// scanner's status and scan.json as file_fnv1a64, a capture's frames).
// Not cryptographic: it tells files apart, it does not authenticate them.

#include <cstddef>
#include <cstdint>

namespace fpp {

inline std::uint64_t fnv1a64(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::uint64_t h = 0xcbf29ce484222325ull; // offset basis
    for (std::size_t i = 0; i < size; ++i) {
        h ^= p[i];
        h *= 0x100000001b3ull; // FNV prime
    }
    return h;
}

} // namespace fpp
