// FNV-1a 64 (fpp/fnv1a.hpp), the fingerprint of files' bytes: the published
// test vectors of the algorithm, every byte value taken unsigned, and one
// changed byte changing the hash.

#include "fpp/fnv1a.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace {

std::uint64_t hash(const std::string& text) {
    return fpp::fnv1a64(text.data(), text.size());
}

TEST(Fnv1a, PublishedTestVectors) {
    // The offset basis for no bytes; then FNV-1a 64's reference values.
    EXPECT_EQ(hash(""), 0xcbf29ce484222325ull);
    EXPECT_EQ(hash("a"), 0xaf63dc4c8601ec8cull);
    EXPECT_EQ(hash("b"), 0xaf63df4c8601f1a5ull);
    EXPECT_EQ(hash("foobar"), 0x85944171f73967e8ull);
    EXPECT_EQ(hash("chongo was here!\n"), 0x46810940eff5f915ull);
}

TEST(Fnv1a, BytesAreTakenUnsignedAndZeroBytesCount) {
    const unsigned char ff = 0xff;
    EXPECT_EQ(fpp::fnv1a64(&ff, 1), 0xaf64724c8602eb6eull);
    const char signed_ff = static_cast<char>(0xff); // negative where char is signed
    EXPECT_EQ(fpp::fnv1a64(&signed_ff, 1), 0xaf64724c8602eb6eull);
    const std::vector<unsigned char> zeros(2, 0);
    EXPECT_EQ(fpp::fnv1a64(zeros.data(), 1), 0xaf63bd4c8601b7dfull);
    EXPECT_EQ(fpp::fnv1a64(zeros.data(), 2), 0x08328807b4eb6fedull);
    EXPECT_NE(fpp::fnv1a64(zeros.data(), 1), hash(""));
}

TEST(Fnv1a, OneChangedByteChangesTheHash) {
    std::string text(4096, 'x');
    const std::uint64_t before = hash(text);
    for (const std::size_t at : {std::size_t(0), std::size_t(2048), text.size() - 1}) {
        std::string changed = text;
        changed[at] = 'y';
        EXPECT_NE(hash(changed), before) << at;
    }
    EXPECT_EQ(hash(text), before); // and the same bytes the same hash
}

} // namespace
