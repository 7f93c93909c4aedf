// The coefficient table file (.fpt): bit-exact round trips, the documented
// byte layout (read back with an independent CRC), and a named InputError for
// every kind of damage; atomic writes; the in-memory table's accessors.

#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"
#include "fpp/fnv1a.hpp"

#include "../../../firmware/core/src/crc32.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/resource.h>

namespace fs = std::filesystem;
using fpp::test::TempDir;

namespace {

using Bytes = std::vector<unsigned char>;

// Bit-by-bit CRC-32 (IEEE, reflected), independent of the table-driven one.
std::uint32_t reference_crc32(const unsigned char* p, std::size_t n) {
    std::uint32_t c = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < n; ++i) {
        c ^= p[i];
        for (int b = 0; b < 8; ++b)
            c = (c >> 1) ^ ((c & 1u) ? 0xEDB88320u : 0u);
    }
    return ~c;
}

std::uint32_t le32(const Bytes& b, std::size_t off) {
    return std::uint32_t(b[off]) | std::uint32_t(b[off + 1]) << 8 |
           std::uint32_t(b[off + 2]) << 16 | std::uint32_t(b[off + 3]) << 24;
}
std::uint64_t le64(const Bytes& b, std::size_t off) {
    return std::uint64_t(le32(b, off)) | std::uint64_t(le32(b, off + 4)) << 32;
}
void put32(Bytes& b, std::size_t off, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        b[off + static_cast<std::size_t>(i)] = static_cast<unsigned char>(v >> (8 * i));
}

Bytes read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return Bytes(std::istreambuf_iterator<char>(in), {});
}
void write_bytes(const fs::path& path, const Bytes& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
}

// Stores a corrected header CRC, so that only the field under test is wrong.
void fix_header_crc(Bytes& b) {
    put32(b, 124, reference_crc32(b.data(), 124));
}

fpp::TableInfo make_info(fpp::TableModel model, fpp::Size camera = {100, 37}, int tw = 32,
                         int th = 8) {
    fpp::TableInfo info;
    info.camera = camera;
    info.tile_width = tw;
    info.tile_height = th;
    info.model = model;
    info.phase_axis = fpp::Axis::y;
    info.projector = {1280, 800};
    info.calibration_hash = 0x0123456789abcdefull;
    info.created_unix_s = 1700000000;
    info.trueness = {150.0f, 478.5f, 0.0191f, 0.0034f};
    return info;
}

// Every pixel distinct and using all mantissa bits; every 7th pixel without a model.
fpp::CoefficientTable make_table(const fpp::TableInfo& info) {
    fpp::CoefficientTable table(info);
    for (int y = 0; y < info.camera.height; ++y) {
        for (int x = 0; x < info.camera.width; ++x) {
            if ((x + 3 * y) % 7 == 0)
                continue;
            table.set(fpp::table_plane::centre, x, y, 400.0f + float(x) * 1.37f + float(y) * 0.61f);
            table.set(fpp::table_plane::inv_half_range, x, y, 1.0f / (120.0f + float(x % 13)));
            for (int k = 2; k < table.planes(); ++k)
                table.set(k, x, y, std::sin(float(x * 31 + y * 17 + k * 7)) * 300.0f);
            if (info.model == fpp::TableModel::rational) // |d| < 1: no pole in range
                table.set(fpp::table_plane::rational_d, x, y, std::sin(float(x + y)) * 0.5f);
        }
    }
    return table;
}

// All bytes of the coefficient block (edge padding included).
std::size_t data_floats(const fpp::CoefficientTable& t) {
    return std::size_t(t.info().tile_count()) * std::size_t(t.planes()) *
           std::size_t(t.info().tile_pixels());
}

void expect_same(const fpp::CoefficientTable& a, const fpp::CoefficientTable& b) {
    const fpp::TableInfo& ia = a.info();
    const fpp::TableInfo& ib = b.info();
    EXPECT_EQ(ia.camera, ib.camera);
    EXPECT_EQ(ia.tile_width, ib.tile_width);
    EXPECT_EQ(ia.tile_height, ib.tile_height);
    EXPECT_EQ(ia.model, ib.model);
    EXPECT_EQ(ia.phase_axis, ib.phase_axis);
    EXPECT_EQ(ia.projector, ib.projector);
    EXPECT_EQ(ia.calibration_hash, ib.calibration_hash);
    EXPECT_EQ(ia.created_unix_s, ib.created_unix_s);
    ASSERT_EQ(a.planes(), b.planes());
    ASSERT_EQ(data_floats(a), data_floats(b));
    EXPECT_EQ(std::memcmp(a.tile(0, 0), b.tile(0, 0), data_floats(a) * sizeof(float)), 0);
    // Through the accessors too (NaN compared by bits).
    for (int y = 0; y < ia.camera.height; ++y)
        for (int x = 0; x < ia.camera.width; ++x)
            for (int k = 0; k < a.planes(); ++k)
                ASSERT_EQ(std::bit_cast<std::uint32_t>(a.get(k, x, y)),
                          std::bit_cast<std::uint32_t>(b.get(k, x, y)))
                    << "plane " << k << " pixel " << x << "," << y;
}

// Loads and returns the InputError's field ("" if it loaded).
std::string load_error_field(const fs::path& path, bool map = true,
                             const fpp::Size* expected = nullptr) {
    try {
        fpp::load_table(path, expected, map);
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), path);
        return e.field();
    }
    return "";
}

std::string load_error_message(const fs::path& path) {
    try {
        fpp::load_table(path);
    } catch (const fpp::InputError& e) {
        return e.what();
    }
    return "";
}

std::vector<std::string> listing(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

// A written table's file and bytes, for damage tests.
struct Written {
    TempDir dir;
    fs::path path;
    Bytes bytes;
    std::size_t data_offset = 0;
    std::size_t tile_bytes = 0;
    int tile_count = 0;
    explicit Written(fpp::TableModel model = fpp::TableModel::polynomial) {
        const fpp::CoefficientTable table = make_table(make_info(model));
        path = dir / "table.fpt";
        fpp::write_table(path, table);
        bytes = read_bytes(path);
        data_offset = std::size_t(le64(bytes, 96));
        tile_bytes = le32(bytes, 84);
        tile_count = int(le32(bytes, 80));
    }
    fs::path damaged(const Bytes& b, const std::string& name = "damaged.fpt") const {
        const fs::path p = dir / name;
        write_bytes(p, b);
        return p;
    }
};

} // namespace

TEST(Crc32, KnownVectors) {
    const std::string check = "123456789";
    EXPECT_EQ(fpp::crc32(check.data(), check.size()), 0xCBF43926u);
    EXPECT_EQ(fpp::crc32("", 0), 0u);
    EXPECT_EQ(fpp::crc32("a", 1), 0xE8B7BE43u);
    const std::string fox = "The quick brown fox jumps over the lazy dog";
    EXPECT_EQ(fpp::crc32(fox.data(), fox.size()), 0x414FA339u);
    // Continued over pieces equals one pass.
    EXPECT_EQ(fpp::crc32(check.data() + 4, 5, fpp::crc32(check.data(), 4)), 0xCBF43926u);
}

TEST(Crc32, MatchesBitwiseReferenceForEveryLengthAndAlignment) {
    Bytes data(300);
    for (std::size_t i = 0; i < data.size(); ++i)
        data[i] = static_cast<unsigned char>(i * 131 + 7);
    for (std::size_t start = 0; start < 9; ++start)
        for (std::size_t n = 0; start + n <= data.size(); n += 7)
            ASSERT_EQ(fpp::crc32(data.data() + start, n), reference_crc32(data.data() + start, n))
                << "start " << start << " length " << n;
}

TEST(Fnv1a64, KnownVectors) {
    EXPECT_EQ(fpp::fnv1a64("", 0), 0xcbf29ce484222325ull);
    EXPECT_EQ(fpp::fnv1a64("a", 1), 0xaf63dc4c8601ec8cull);
    EXPECT_EQ(fpp::fnv1a64("foobar", 6), 0x85944171f73967e8ull);
}

TEST(TableModel, NamesAndPlanes) {
    EXPECT_STREQ(fpp::to_string(fpp::TableModel::polynomial), "polynomial");
    EXPECT_STREQ(fpp::to_string(fpp::TableModel::ray), "ray");
    EXPECT_EQ(fpp::parse_table_model("polynomial"), fpp::TableModel::polynomial);
    EXPECT_EQ(fpp::parse_table_model("ray"), fpp::TableModel::ray);
    EXPECT_THROW(fpp::parse_table_model("cubic"), std::invalid_argument);
    EXPECT_EQ(fpp::table_planes(fpp::TableModel::polynomial), 14);
    EXPECT_EQ(fpp::table_planes(fpp::TableModel::ray), 8);
    EXPECT_STREQ(fpp::to_string(fpp::TableModel::rational), "rational");
    EXPECT_EQ(fpp::parse_table_model("rational"), fpp::TableModel::rational);
    EXPECT_EQ(fpp::table_planes(fpp::TableModel::rational), 9);
}

TEST(CoefficientTable, NewTableHasNoModelAnywhere) {
    const fpp::TableInfo info = make_info(fpp::TableModel::ray);
    fpp::CoefficientTable table(info);
    EXPECT_FALSE(table.empty());
    EXPECT_FALSE(table.mapped());
    EXPECT_EQ(table.planes(), 8);
    EXPECT_EQ(info.tiles_x(), 4);
    EXPECT_EQ(info.tiles_y(), 5);
    for (int y = 0; y < 37; ++y) {
        for (int x = 0; x < 100; ++x) {
            ASSERT_FALSE(table.has_model(x, y));
            ASSERT_TRUE(std::isnan(table.get(fpp::table_plane::centre, x, y)));
            for (int k = 1; k < 8; ++k)
                ASSERT_EQ(table.get(k, x, y), 0.0f);
        }
    }
    table.set(fpp::table_plane::centre, 99, 36, 5.0f);
    EXPECT_TRUE(table.has_model(99, 36));
    // The last pixel lives in the last (edge) tile, at its documented place.
    const float* last = table.tile(3, 4);
    EXPECT_EQ(last[(36 - 32) * 32 + (99 - 96)], 5.0f);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(table.tile(0, 0)) % 64, 0u);
}

TEST(CoefficientTable, RejectsBadLayoutsAndIndices) {
    auto info = make_info(fpp::TableModel::ray);
    info.tile_width = 12;
    EXPECT_THROW(fpp::CoefficientTable{info}, std::invalid_argument);
    info.tile_width = 264;
    EXPECT_THROW(fpp::CoefficientTable{info}, std::invalid_argument);
    info = make_info(fpp::TableModel::ray, {0, 10});
    EXPECT_THROW(fpp::CoefficientTable{info}, std::invalid_argument);
    info = make_info(fpp::TableModel::ray);
    info.projector = {0, 800};
    EXPECT_THROW(fpp::CoefficientTable{info}, std::invalid_argument);
    info = make_info(static_cast<fpp::TableModel>(4));
    EXPECT_THROW(fpp::CoefficientTable{info}, std::invalid_argument);

    fpp::CoefficientTable table(make_info(fpp::TableModel::ray));
    EXPECT_THROW(table.get(0, 100, 0), std::out_of_range);
    EXPECT_THROW(table.get(0, 0, -1), std::out_of_range);
    EXPECT_THROW(table.get(8, 0, 0), std::out_of_range);
    EXPECT_THROW(table.set(0, 0, 37, 1.0f), std::out_of_range);
}

TEST(CoefficientTable, MoveLeavesTheSourceEmpty) {
    fpp::CoefficientTable a(make_info(fpp::TableModel::ray));
    a.set(fpp::table_plane::ray_xn, 3, 4, 0.25f);
    fpp::CoefficientTable b(std::move(a));
    EXPECT_TRUE(a.empty()); // NOLINT(bugprone-use-after-move): the moved-from state is specified
    EXPECT_EQ(b.get(fpp::table_plane::ray_xn, 3, 4), 0.25f);
    fpp::CoefficientTable c;
    EXPECT_TRUE(c.empty());
    c = std::move(b);
    EXPECT_TRUE(b.empty()); // NOLINT(bugprone-use-after-move)
    EXPECT_EQ(c.get(fpp::table_plane::ray_xn, 3, 4), 0.25f);
}

TEST(TableFile, RoundTripIsBitExactForBothModelsAndTileSizes) {
    TempDir dir;
    struct Case {
        fpp::TableModel model;
        fpp::Size camera;
        int tw, th;
    };
    const Case cases[] = {{fpp::TableModel::polynomial, {100, 37}, 32, 8},
                          {fpp::TableModel::ray, {100, 37}, 32, 8},
                          {fpp::TableModel::rational, {100, 37}, 32, 8},
                          {fpp::TableModel::ray, {100, 37}, 256, 64},
                          {fpp::TableModel::polynomial, {64, 16}, 8, 16},
                          {fpp::TableModel::polynomial, {1, 1}, 8, 8}};
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(fpp::to_string(c.model)) + " " + std::to_string(c.camera.width) +
                     "x" + std::to_string(c.camera.height) + " tiles " + std::to_string(c.tw) +
                     "x" + std::to_string(c.th));
        const fpp::CoefficientTable table = make_table(make_info(c.model, c.camera, c.tw, c.th));
        const fs::path path = dir / "t.fpt";
        fpp::write_table(path, table);
        const fpp::CoefficientTable mapped = fpp::load_table(path, &c.camera, true);
        EXPECT_TRUE(mapped.mapped());
        expect_same(table, mapped);
        const fpp::CoefficientTable read = fpp::load_table(path, nullptr, false);
        EXPECT_FALSE(read.mapped());
        expect_same(table, read);
        // Written again from the mapping: the same bytes.
        const Bytes first = read_bytes(path);
        fpp::write_table(dir / "again.fpt", mapped);
        EXPECT_EQ(read_bytes(dir / "again.fpt"), first);
    }
}

TEST(TableFile, LayoutIsAsDocumented) {
    const fpp::TableInfo info = make_info(fpp::TableModel::polynomial);
    const fpp::CoefficientTable table = make_table(info);
    TempDir dir;
    fpp::write_table(dir / "t.fpt", table);
    const Bytes b = read_bytes(dir / "t.fpt");
    ASSERT_GE(b.size(), 128u);
    EXPECT_EQ(std::string(b.begin(), b.begin() + 8), "FPPTABLE");
    EXPECT_EQ(le32(b, 8), 2u);    // version
    EXPECT_EQ(le32(b, 12), 128u); // header size
    EXPECT_EQ(le32(b, 16), 100u);
    EXPECT_EQ(le32(b, 20), 37u);
    EXPECT_EQ(le32(b, 24), 32u);
    EXPECT_EQ(le32(b, 28), 8u);
    EXPECT_EQ(le32(b, 32), 1u);  // polynomial
    EXPECT_EQ(le32(b, 36), 14u); // planes
    EXPECT_EQ(le32(b, 40), 1u);  // phase axis y
    EXPECT_EQ(le32(b, 44), 1280u);
    EXPECT_EQ(le32(b, 48), 800u);
    EXPECT_EQ(le32(b, 52), 1u); // projector pixels
    EXPECT_EQ(le64(b, 56), 0x0123456789abcdefull);
    EXPECT_EQ(le64(b, 64), 1700000000ull);
    EXPECT_EQ(le32(b, 72), 4u);
    EXPECT_EQ(le32(b, 76), 5u);
    EXPECT_EQ(le32(b, 80), 20u);
    const std::size_t tile_bytes = 14 * 32 * 8 * 4;
    EXPECT_EQ(le32(b, 84), tile_bytes);
    EXPECT_EQ(le64(b, 88), 128u);
    const std::size_t data_offset = std::size_t(le64(b, 96));
    EXPECT_EQ(data_offset, 4096u); // 128 + 20 * 4 + 4 rounded up to 4096
    // The trueness: length, depth, along depth, across (float32).
    EXPECT_EQ(le32(b, 104), std::bit_cast<std::uint32_t>(150.0f));
    EXPECT_EQ(le32(b, 108), std::bit_cast<std::uint32_t>(478.5f));
    EXPECT_EQ(le32(b, 112), std::bit_cast<std::uint32_t>(0.0191f));
    EXPECT_EQ(le32(b, 116), std::bit_cast<std::uint32_t>(0.0034f));
    for (std::size_t i = 120; i < 124; ++i)
        EXPECT_EQ(b[i], 0) << "reserved byte " << i;
    EXPECT_EQ(le32(b, 124), reference_crc32(b.data(), 124));
    EXPECT_EQ(le32(b, 128 + 20 * 4), reference_crc32(b.data() + 128, 20 * 4));
    for (std::size_t i = 128 + 21 * 4; i < data_offset; ++i)
        ASSERT_EQ(b[i], 0) << "padding " << i;
    ASSERT_EQ(b.size(), data_offset + 20 * tile_bytes);
    for (std::size_t t = 0; t < 20; ++t)
        EXPECT_EQ(le32(b, 128 + 4 * t),
                  reference_crc32(b.data() + data_offset + t * tile_bytes, tile_bytes))
            << "tile " << t;
    // Pixel (x, y), plane k: tile (x / 32, y / 8), row-major inside the plane.
    const auto at = [&](int k, int x, int y) {
        const std::size_t tile = std::size_t(y / 8) * 4 + std::size_t(x / 32);
        const std::size_t i = std::size_t((y % 8) * 32 + x % 32);
        const std::size_t off = data_offset + tile * tile_bytes + (std::size_t(k) * 256 + i) * 4;
        return std::bit_cast<float>(le32(b, off));
    };
    const std::pair<int, int> pixels[] = {{1, 0}, {45, 9}, {99, 36}, {31, 35}};
    for (const auto& [x, y] : pixels)
        for (int k = 0; k < 14; ++k)
            EXPECT_EQ(std::bit_cast<std::uint32_t>(at(k, x, y)),
                      std::bit_cast<std::uint32_t>(table.get(k, x, y)))
                << "plane " << k << " pixel " << x << "," << y;
    // Edge padding: no model (NaN centre), zero coefficients.
    EXPECT_TRUE(std::isnan(at(0, 0, 0))); // (0 + 0) % 7 == 0: no model
    const std::size_t pad = data_offset + 19 * tile_bytes + (std::size_t(7) * 32 + 31) * 4;
    EXPECT_EQ(le32(b, pad), 0x7FC00000u);
    EXPECT_EQ(le32(b, pad + 5 * 256 * 4), 0u);
}

TEST(TableFile, FlippedBitInAnyTileNamesThatTile) {
    const Written w;
    ASSERT_EQ(w.tile_count, 20);
    for (const int tile : {0, 1, 7, 19}) {
        for (const std::size_t offset : {std::size_t(0), w.tile_bytes / 2 + 3, w.tile_bytes - 1}) {
            Bytes b = w.bytes;
            b[w.data_offset + std::size_t(tile) * w.tile_bytes + offset] ^= 0x10;
            const fs::path p = w.damaged(b);
            const std::string field = "tile " + std::to_string(tile) + " crc";
            EXPECT_EQ(load_error_field(p, true), field) << "offset " << offset;
            EXPECT_EQ(load_error_field(p, false), field) << "offset " << offset;
        }
    }
}

TEST(TableFile, FlippedBitInHeaderOrCrcTable) {
    const Written w;
    for (const std::size_t byte : {12, 16, 23, 33, 41, 52, 60, 70, 80, 90, 100, 110, 124, 127}) {
        Bytes b = w.bytes;
        b[byte] ^= 0x01;
        EXPECT_EQ(load_error_field(w.damaged(b)), byte == 12 ? "header_size" : "header crc")
            << "byte " << byte;
    }
    for (const std::size_t byte : {128, 128 + 4 * 19 + 2, 128 + 4 * 20 + 3}) {
        Bytes b = w.bytes;
        b[byte] ^= 0x80;
        EXPECT_EQ(load_error_field(w.damaged(b)), "crc table crc") << "byte " << byte;
    }
    Bytes b = w.bytes;
    b[w.data_offset - 1] = 1;
    EXPECT_EQ(load_error_field(w.damaged(b)), "padding");
    Bytes clean = w.bytes;
    EXPECT_EQ(load_error_field(w.damaged(clean)), ""); // the copy itself is fine
}

TEST(TableFile, WrongMagicAndUnknownVersion) {
    const Written w;
    Bytes b = w.bytes;
    b[3] = 'X';
    EXPECT_EQ(load_error_field(w.damaged(b)), "magic");
    EXPECT_EQ(load_error_field(w.damaged(Bytes{})), "magic");
    EXPECT_EQ(load_error_field(w.damaged(Bytes{'F', 'P', 'P'})), "magic");
    write_bytes(w.dir / "text.fpt",
                Bytes{'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd', '\n'});
    EXPECT_EQ(load_error_field(w.dir / "text.fpt"), "magic");

    for (const std::uint32_t version : {0u, 3u}) {
        b = w.bytes;
        put32(b, 8, version);
        fix_header_crc(b);
        const fs::path other = w.damaged(b);
        EXPECT_EQ(load_error_field(other), "version");
        const std::string message = load_error_message(other);
        EXPECT_NE(message.find("unsupported version " + std::to_string(version)), std::string::npos)
            << message;
        EXPECT_NE(message.find("reads versions 1 to 2"), std::string::npos) << message;
    }
}

// A version-1 table (the trueness bytes reserved and zero) still loads, with
// the trueness unknown; one with those bytes set is refused.
TEST(TableFile, VersionOneLoadsWithTheTruenessUnknown) {
    const Written w;
    Bytes b = w.bytes;
    put32(b, 8, 1);
    for (std::size_t i = 104; i < 120; ++i)
        b[i] = 0;
    fix_header_crc(b);
    const fs::path v1 = w.damaged(b);
    const fpp::CoefficientTable t = fpp::load_table(v1, nullptr, false);
    EXPECT_FALSE(t.info().trueness.known());
    EXPECT_EQ(t.info().trueness.along_depth_mm, 0.0f);
    EXPECT_EQ(t.info().calibration_hash, 0x0123456789abcdefull);
    b = w.bytes;
    put32(b, 8, 1);
    fix_header_crc(b);
    EXPECT_EQ(load_error_field(w.damaged(b)), "reserved");
}

TEST(TableFile, TruenessIsReadBackAndChecked) {
    const Written w;
    const fpp::CoefficientTable t = fpp::load_table(w.path, nullptr, false);
    EXPECT_EQ(t.info().trueness.length_mm, 150.0f);
    EXPECT_EQ(t.info().trueness.depth_mm, 478.5f);
    EXPECT_EQ(t.info().trueness.along_depth_mm, 0.0191f);
    EXPECT_EQ(t.info().trueness.across_mm, 0.0034f);
    struct Patch {
        std::size_t offset;
        float value;
        const char* field;
    };
    const Patch patches[] = {
        {104, -150.0f, "trueness_length_mm"},
        {108, std::numeric_limits<float>::quiet_NaN(), "trueness_depth_mm"},
        {108, 0.0f, "trueness_depth_mm"},
        {112, std::numeric_limits<float>::infinity(), "trueness_along_depth_mm"},
        {116, -0.001f, "trueness_across_mm"},
        {104, 0.0f, "trueness_length_mm"}}; // unknown, the rest not 0
    for (const Patch& p : patches) {
        Bytes b = w.bytes;
        put32(b, p.offset, std::bit_cast<std::uint32_t>(p.value));
        fix_header_crc(b);
        EXPECT_EQ(load_error_field(w.damaged(b)), p.field) << "offset " << p.offset;
    }
    // The header's provenance set after the fit: written and read back,
    // refused (and left as it was) when the file could not hold it.
    fpp::CoefficientTable later = make_table(make_info(fpp::TableModel::ray));
    later.set_provenance(0x1122334455667788ull, {150.0f, 500.0f, 0.01f, 0.002f});
    fpp::write_table(w.dir / "later.fpt", later);
    const fpp::CoefficientTable back = fpp::load_table(w.dir / "later.fpt", nullptr, false);
    EXPECT_EQ(back.info().calibration_hash, 0x1122334455667788ull);
    EXPECT_EQ(back.info().trueness.depth_mm, 500.0f);
    EXPECT_EQ(back.info().trueness.along_depth_mm, 0.01f);
    EXPECT_THROW(later.set_provenance(1, {150.0f, 0.0f, 0.01f, 0.002f}), std::invalid_argument);
    EXPECT_EQ(later.info().calibration_hash, 0x1122334455667788ull);
    // The writer refuses what the loader would.
    fpp::TableInfo info = make_info(fpp::TableModel::ray);
    info.trueness.across_mm = -1;
    EXPECT_THROW(fpp::write_table(w.dir / "bad.fpt", make_table(info)), std::invalid_argument);
    EXPECT_FALSE(fs::exists(w.dir / "bad.fpt"));
}

TEST(TableFile, TruncatedOrExtendedFile) {
    const Written w;
    for (const std::size_t size :
         {std::size_t(10), std::size_t(100), std::size_t(200), w.data_offset,
          w.data_offset + 3 * w.tile_bytes + 5, w.bytes.size() - 1}) {
        const Bytes b(w.bytes.begin(), w.bytes.begin() + static_cast<std::ptrdiff_t>(size));
        EXPECT_EQ(load_error_field(w.damaged(b)), "file size (truncated)") << size << " bytes";
    }
    Bytes b = w.bytes;
    b.push_back(0);
    EXPECT_EQ(load_error_field(w.damaged(b)), "file size (extra bytes)");
    b.resize(b.size() + 4095, 0);
    EXPECT_EQ(load_error_field(w.damaged(b), false), "file size (extra bytes)");
}

TEST(TableFile, CameraSizeMustMatchTheExpectedOne) {
    const Written w;
    const fpp::Size right{100, 37};
    const fpp::Size wrong{1600, 1200};
    EXPECT_EQ(load_error_field(w.path, true, &right), "");
    EXPECT_EQ(load_error_field(w.path, true, &wrong), "camera_size");
    EXPECT_EQ(load_error_field(w.path, false, &wrong), "camera_size");
}

TEST(TableFile, HeaderFieldsOutOfRangeAreNamed) {
    const Written w;
    struct Patch {
        std::size_t offset;
        std::uint32_t value;
        const char* field;
    };
    const Patch patches[] = {{16, 0, "camera_width"},    {20, 70000, "camera_height"},
                             {24, 12, "tile_width"},     {28, 512, "tile_height"},
                             {32, 4, "model"},           {32, 2, "planes"},
                             {36, 8, "planes"},          {40, 2, "phase_axis"},
                             {44, 0, "projector_width"}, {52, 0, "phase_unit"},
                             {72, 5, "tiles_x"},         {80, 21, "tile_count"},
                             {84, 1024, "tile_bytes"},   {88, 256, "crc_table_offset"},
                             {96, 8192, "data_offset"},  {100, 1, "data_offset"},
                             {120, 7, "reserved"},       {16, 0x80000000u, "camera_width"}};
    for (const Patch& p : patches) {
        Bytes b = w.bytes;
        put32(b, p.offset, p.value);
        fix_header_crc(b);
        EXPECT_EQ(load_error_field(w.damaged(b)), p.field)
            << "offset " << p.offset << " = " << p.value;
    }
}

TEST(TableFile, InvalidCoefficientsAreRejectedOnLoadAndOnWrite) {
    const Written w;
    // Pixel (33, 9) lies in tile (1, 1) = tile 5 at index (9 - 8) * 32 + 1; it has a model.
    const std::size_t tile = 5;
    const std::size_t i = 32 + 1;
    const std::size_t tile_start = w.data_offset + tile * w.tile_bytes;
    const float bad[] = {0.0f, -0.01f, std::numeric_limits<float>::infinity()};
    for (const float value : bad) {
        Bytes b = w.bytes;
        put32(b, tile_start + (1 * 256 + i) * 4, std::bit_cast<std::uint32_t>(value));
        put32(b, 128 + 4 * tile, reference_crc32(b.data() + tile_start, w.tile_bytes));
        put32(b, 128 + 4 * 20, reference_crc32(b.data() + 128, 4 * 20));
        const fs::path p = w.damaged(b);
        EXPECT_EQ(load_error_field(p), "tile 5 values") << value;
        EXPECT_NE(load_error_message(p).find("pixel (33, 9)"), std::string::npos)
            << load_error_message(p);
    }

    fpp::CoefficientTable table = make_table(make_info(fpp::TableModel::ray));
    ASSERT_TRUE(table.has_model(33, 9));
    table.set(fpp::table_plane::ray_z + 2, 33, 9, std::numeric_limits<float>::quiet_NaN());
    EXPECT_THROW(fpp::write_table(w.dir / "bad.fpt", table), std::invalid_argument);
    EXPECT_FALSE(fs::exists(w.dir / "bad.fpt"));
    // Without a model the other planes do not matter.
    table.set(fpp::table_plane::centre, 33, 9, std::numeric_limits<float>::quiet_NaN());
    EXPECT_NO_THROW(fpp::write_table(w.dir / "ok.fpt", table));

    // A rational pixel whose denominator 1 + d t vanishes inside |t| <= 1.
    fpp::CoefficientTable rational = make_table(make_info(fpp::TableModel::rational));
    EXPECT_NO_THROW(fpp::write_table(w.dir / "rational.fpt", rational));
    rational.set(fpp::table_plane::rational_d, 33, 9, -1.0f);
    EXPECT_THROW(fpp::write_table(w.dir / "pole.fpt", rational), std::invalid_argument);
    EXPECT_FALSE(fs::exists(w.dir / "pole.fpt"));
}

TEST(TableFile, MissingFileIsAnIoError) {
    TempDir dir;
    EXPECT_THROW(fpp::load_table(dir / "none.fpt"), fpp::IoError);
    EXPECT_THROW(fpp::load_table(dir.path()), std::exception);
}

TEST(TableFile, MappedTableIsReadOnlyAndOutlivesReplacement) {
    TempDir dir;
    const fs::path path = dir / "t.fpt";
    fpp::write_table(path, make_table(make_info(fpp::TableModel::ray)));
    const fpp::CoefficientTable mapped = fpp::load_table(path);
    fpp::CoefficientTable writable = fpp::load_table(path, nullptr, false);
    const float before = mapped.get(fpp::table_plane::ray_xn, 10, 10);
    EXPECT_THROW(const_cast<fpp::CoefficientTable&>(mapped).set(0, 0, 0, 1.0f), std::logic_error);
    writable.set(fpp::table_plane::ray_xn, 10, 10, before + 1.0f);
    // Replacing the file (atomically, a new inode) leaves the mapping intact.
    fpp::write_table(path, writable);
    EXPECT_EQ(mapped.get(fpp::table_plane::ray_xn, 10, 10), before);
    EXPECT_EQ(fpp::load_table(path).get(fpp::table_plane::ray_xn, 10, 10), before + 1.0f);
}

TEST(TableFile, WriteReplacesOnlyOnSuccessAndLeavesNoTemporaryFile) {
    TempDir dir;
    const fs::path path = dir / "t.fpt";
    write_bytes(path, Bytes{'o', 'l', 'd'});
    const fpp::CoefficientTable table = make_table(make_info(fpp::TableModel::polynomial));
    fpp::write_table(path, table);
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"t.fpt"});
    expect_same(table, fpp::load_table(path));
    const Bytes good = read_bytes(path);

    // A write failing half-way (file size limit: write() fails with EFBIG)
    // leaves the previous file untouched and no temporary file behind.
    const fpp::CoefficientTable other = make_table(make_info(fpp::TableModel::ray, {200, 100}));
    rlimit saved{};
    ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
    const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
    rlimit small = saved;
    small.rlim_cur = 16384;
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
    bool threw = false;
    try {
        fpp::write_table(path, other);
    } catch (const fpp::IoError&) {
        threw = true;
    }
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &saved), 0);
    std::signal(SIGXFSZ, old_handler);
    EXPECT_TRUE(threw);
    EXPECT_EQ(read_bytes(path), good);
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"t.fpt"});

    // A target that cannot be replaced (a folder): IoError, no leftovers.
    fs::create_directory(dir / "folder.fpt");
    fs::create_directory(dir / "folder.fpt" / "inside");
    EXPECT_THROW(fpp::write_table(dir / "folder.fpt", table), fpp::IoError);
    EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{"folder.fpt", "t.fpt"}));
}
