// PNG and float TIFF reading/writing: exact round trips, byte order against
// independently encoded fixtures (tests/data/image_io/make_fixtures.py),
// rejection of the wrong kinds of image, corrupt files, failed writes; and the
// Image container's moved-from state.

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/yaml_fields.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

namespace fs = std::filesystem;
using fpp::test::TempDir;

namespace {

fs::path fixture(const std::string& name) {
    return fpp::test::source_dir() / "tests" / "data" / "image_io" / name;
}

template <class T> fpp::Image<T> random_image(int w, int h, int c, std::uint32_t seed) {
    fpp::Image<T> image(w, h, c);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> dist(0, std::numeric_limits<T>::max());
    for (auto& v : image.storage())
        v = static_cast<T>(dist(rng));
    return image;
}

std::vector<fs::path> listing(const fs::path& folder) {
    std::vector<fs::path> names;
    for (const auto& e : fs::directory_iterator(folder))
        names.push_back(e.path().filename());
    return names;
}

void truncate_file(const fs::path& path, std::uintmax_t size) {
    fs::resize_file(path, size);
}

// Runs f, expecting InputError whose message names `path`.
template <class F> void expect_input_error_naming(const fs::path& path, F&& f) {
    try {
        f();
        ADD_FAILURE() << "no InputError for " << path;
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
}

std::uint32_t bits_of(float f) {
    return std::bit_cast<std::uint32_t>(f);
}

} // namespace

// A moved-from image is 0x0 and empty, so that code that checks a recycled
// image's size before reusing it never takes one without pixels.
TEST(Image, MovedFromImageIsEmptyWithNoSize) {
    fpp::Image<float> a(5, 4, 3, 1.5f);
    fpp::Image<float> b(std::move(a));
    EXPECT_EQ(b.size(), (fpp::Size{5, 4}));
    EXPECT_EQ(b.channels(), 3);
    EXPECT_EQ(b.at(4, 3, 2), 1.5f);
    EXPECT_TRUE(a.empty()); // NOLINT(bugprone-use-after-move): the moved-from state is the subject
    EXPECT_EQ(a.size(), (fpp::Size{0, 0}));
    EXPECT_EQ(a.pixel_count(), 0u);
    fpp::Image<float> c(2, 2);
    c = std::move(b);
    EXPECT_EQ(c.size(), (fpp::Size{5, 4}));
    EXPECT_EQ(b.size(), (fpp::Size{0, 0}));
    EXPECT_TRUE(b.empty());
    fpp::Image<float>& same = c;
    c = std::move(same); // self-move keeps the image
    EXPECT_EQ(c.size(), (fpp::Size{5, 4}));
    EXPECT_EQ(c.pixel_count() * 3, c.storage().size());
}

TEST(ImageIo, Png8BitRoundTripIsExact) {
    TempDir dir;
    const auto image = random_image<std::uint8_t>(37, 23, 1, 1);
    write_png(dir / "a.png", image);
    const fpp::Frame frame = fpp::read_png_gray(dir / "a.png");
    EXPECT_EQ(frame.bit_depth, 8);
    ASSERT_EQ(frame.u8.size(), image.size());
    EXPECT_TRUE(frame.u16.empty());
    EXPECT_EQ(frame.u8.storage(), image.storage());
    // Only the target remains: no temporary file.
    EXPECT_EQ(listing(dir.path()), std::vector<fs::path>{"a.png"});
}

TEST(ImageIo, Png16BitRoundTripIsExact) {
    TempDir dir;
    auto image = random_image<std::uint16_t>(41, 17, 1, 2);
    image.at(0, 0) = 0;
    image.at(1, 0) = 65535;
    image.at(2, 0) = 0x0102;
    write_png(dir / "b.png", image);
    const fpp::Frame frame = fpp::read_png_gray(dir / "b.png");
    EXPECT_EQ(frame.bit_depth, 16);
    ASSERT_EQ(frame.u16.size(), image.size());
    EXPECT_TRUE(frame.u8.empty());
    EXPECT_EQ(frame.u16.storage(), image.storage());
}

TEST(ImageIo, FrameWriterKeepsDepth) {
    TempDir dir;
    fpp::Frame f16;
    f16.bit_depth = 16;
    f16.u16 = random_image<std::uint16_t>(5, 4, 1, 3);
    write_png(dir / "f16.png", f16);
    const auto info = fpp::read_png_info(dir / "f16.png");
    EXPECT_EQ(info.bit_depth, 16);
    EXPECT_EQ(info.channels, 1);
    EXPECT_EQ(info.size, (fpp::Size{5, 4}));
    EXPECT_EQ(fpp::read_png_gray(dir / "f16.png").u16.storage(), f16.u16.storage());

    fpp::Frame bad;
    bad.bit_depth = 12;
    bad.u16 = f16.u16;
    EXPECT_THROW(write_png(dir / "bad.png", bad), std::invalid_argument);
    EXPECT_FALSE(fs::exists(dir / "bad.png"));
}

TEST(ImageIo, Rgb8PngWritesThreeChannels) {
    TempDir dir;
    const auto image = random_image<std::uint8_t>(6, 5, 3, 4);
    write_png(dir / "rgb.png", image);
    const auto info = fpp::read_png_info(dir / "rgb.png");
    EXPECT_EQ(info.channels, 3);
    EXPECT_EQ(info.bit_depth, 8);
    // A colour PNG is not a frame.
    expect_input_error_naming(dir / "rgb.png", [&] { fpp::read_png_gray(dir / "rgb.png"); });
}

TEST(ImageIo, UnsupportedChannelCountsAreRefusedBeforeWriting) {
    TempDir dir;
    EXPECT_THROW(write_png(dir / "x.png", fpp::Image<std::uint8_t>(4, 4, 2)),
                 std::invalid_argument);
    EXPECT_THROW(write_png(dir / "y.png", fpp::Image<std::uint16_t>(4, 4, 3)),
                 std::invalid_argument);
    EXPECT_THROW(write_png(dir / "z.png", fpp::Image<std::uint8_t>()), std::invalid_argument);
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(ImageIo, Reads16BitFixtureBigEndian) {
    // Encoded by make_fixtures.py: samples stored big-endian as PNG specifies.
    const fpp::Frame frame = fpp::read_png_gray(fixture("gray16_3x2.png"));
    ASSERT_EQ(frame.bit_depth, 16);
    ASSERT_EQ(frame.u16.size(), (fpp::Size{3, 2}));
    const std::vector<std::uint16_t> expected = {0x0102, 0xFFFE, 0x0000, 0x0001, 0x8000, 0x1234};
    EXPECT_EQ(frame.u16.storage(), expected);
}

TEST(ImageIo, Written16BitPngStoresBigEndianSamples) {
    // The reader is pinned by the independently encoded fixture (above); a
    // writer storing little-endian samples would make this copy read back
    // byte-swapped.
    TempDir dir;
    const fpp::Frame fixture_frame = fpp::read_png_gray(fixture("gray16_3x2.png"));
    write_png(dir / "copy.png", fixture_frame);
    EXPECT_EQ(fpp::read_png_gray(dir / "copy.png").u16.storage(), fixture_frame.u16.storage());
}

TEST(ImageIo, ReadsInterlacedPng) {
    const fpp::Frame frame = fpp::read_png_gray(fixture("gray8_adam7_9x7.png"));
    ASSERT_EQ(frame.u8.size(), (fpp::Size{9, 7}));
    for (int y = 0; y < 7; ++y) {
        for (int x = 0; x < 9; ++x)
            EXPECT_EQ(frame.u8.at(x, y), 10 * y + x) << x << "," << y;
    }
}

TEST(ImageIo, RejectsColourPaletteAlphaAndOtherDepths) {
    for (const char* name : {"rgb8_2x2.png", "gray_alpha8_2x2.png", "rgba8_2x2.png",
                             "palette8_2x2.png", "gray4_4x2.png"}) {
        SCOPED_TRACE(name);
        expect_input_error_naming(fixture(name), [&] { fpp::read_png_gray(fixture(name)); });
    }
    const auto palette = fpp::read_png_info(fixture("palette8_2x2.png"));
    EXPECT_TRUE(palette.palette);
    EXPECT_EQ(fpp::read_png_info(fixture("gray_alpha8_2x2.png")).channels, 2);
    EXPECT_EQ(fpp::read_png_info(fixture("gray4_4x2.png")).bit_depth, 4);
}

TEST(ImageIo, MissingPngIsInputError) {
    TempDir dir;
    expect_input_error_naming(dir / "none.png", [&] { fpp::read_png_gray(dir / "none.png"); });
    expect_input_error_naming(dir / "none.png", [&] { fpp::read_png_info(dir / "none.png"); });
}

TEST(ImageIo, TruncatedPngIsInputErrorAtEveryLength) {
    TempDir dir;
    const auto image = random_image<std::uint8_t>(64, 48, 1, 5);
    write_png(dir / "full.png", image);
    const auto full_size = fs::file_size(dir / "full.png");
    // Cuts from an empty file to one byte short of the end (IEND damaged).
    std::vector<std::uintmax_t> cuts;
    for (std::uintmax_t cut = 0; cut < full_size; cut += (cut < 64 ? 1 : 97))
        cuts.push_back(cut);
    cuts.push_back(full_size - 12); // exactly the IEND chunk missing
    cuts.push_back(full_size - 1);
    for (const std::uintmax_t cut : cuts) {
        SCOPED_TRACE(cut);
        fs::copy_file(dir / "full.png", dir / "cut.png", fs::copy_options::overwrite_existing);
        truncate_file(dir / "cut.png", cut);
        expect_input_error_naming(dir / "cut.png", [&] { fpp::read_png_gray(dir / "cut.png"); });
    }
}

TEST(ImageIo, CorruptPngIsInputError) {
    TempDir dir;
    const auto image = random_image<std::uint8_t>(64, 48, 1, 6);
    write_png(dir / "ok.png", image);
    std::string bytes(fs::file_size(dir / "ok.png"), '\0');
    std::ifstream(dir / "ok.png", std::ios::binary)
        .read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    // Flip a byte inside the compressed data: the chunk CRC no longer matches.
    std::string corrupt = bytes;
    corrupt[corrupt.size() / 2] = static_cast<char>(corrupt[corrupt.size() / 2] ^ 0x5a);
    std::ofstream(dir / "corrupt.png", std::ios::binary) << corrupt;
    expect_input_error_naming(dir / "corrupt.png",
                              [&] { fpp::read_png_gray(dir / "corrupt.png"); });
    // Not a PNG at all.
    std::ofstream(dir / "text.png", std::ios::binary) << "format: fpp-capture/1\n";
    expect_input_error_naming(dir / "text.png", [&] { fpp::read_png_gray(dir / "text.png"); });
    // A header claiming an absurd size.
    std::string huge = bytes;
    huge[16] = '\x7f'; // width's most significant byte (IHDR CRC now wrong too)
    std::ofstream(dir / "huge.png", std::ios::binary) << huge;
    expect_input_error_naming(dir / "huge.png", [&] { fpp::read_png_gray(dir / "huge.png"); });
}

TEST(ImageIo, PngWriteIntoMissingFolderFailsCleanly) {
    TempDir dir;
    const auto image = random_image<std::uint8_t>(8, 8, 1, 7);
    EXPECT_THROW(write_png(dir / "no" / "such" / "a.png", image), fpp::IoError);
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(ImageIo, PngWriteOnFullDiskSaysNoSpace) {
    // /dev/full fails every write with ENOSPC.
    if (!fs::exists("/dev/full"))
        GTEST_SKIP() << "/dev/full not available";
    fpp::Frame frame;
    frame.u8 = random_image<std::uint8_t>(256, 256, 1, 8); // incompressible: forces real writes
    try {
        fpp::write_png_synced("/dev/full", frame);
        FAIL() << "no error";
    } catch (const fpp::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("no space left"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("/dev/full"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, FloatTiffRoundTripIsBitExactForOneToFourChannels) {
    TempDir dir;
    for (int channels = 1; channels <= 4; ++channels) {
        SCOPED_TRACE(channels);
        fpp::Image<float> image(53, 29, channels);
        std::mt19937 rng(static_cast<std::uint32_t>(channels));
        std::uniform_real_distribution<float> dist(-1000.0f, 1000.0f);
        for (auto& v : image.storage())
            v = dist(rng);
        // Special values, including NaNs with payloads and signs.
        auto& s = image.storage();
        s[0] = std::numeric_limits<float>::quiet_NaN();
        s[1] = std::bit_cast<float>(0x7fc12345u);
        s[2] = std::bit_cast<float>(0xffc00001u);
        s[3] = -0.0f;
        s[4] = std::numeric_limits<float>::infinity();
        s[5] = -std::numeric_limits<float>::infinity();
        s[6] = std::numeric_limits<float>::denorm_min();
        s[7] = 523.123456f;
        // A NaN background, as in truth maps.
        for (std::size_t i = s.size() / 2; i < s.size(); i += 3)
            s[i] = std::nanf("");

        const fs::path path = dir / (std::to_string(channels) + "ch.tiff");
        fpp::write_tiff(path, image);
        const fpp::Image<float> back = fpp::read_tiff_float(path);
        ASSERT_EQ(back.size(), image.size());
        ASSERT_EQ(back.channels(), channels);
        ASSERT_EQ(std::memcmp(back.data(), image.data(), s.size() * sizeof(float)), 0);
        EXPECT_EQ(bits_of(back.storage()[1]), 0x7fc12345u);
        EXPECT_EQ(bits_of(back.storage()[2]), 0xffc00001u);
    }
    // Nothing but the four outputs.
    EXPECT_EQ(listing(dir.path()).size(), 4u);
}

TEST(ImageIo, FloatTiffThreeChannelValuesOfAboutFiveHundredAreExact) {
    // The case OpenCV gets wrong (pitfalls.md): 3-channel XYZ around 500 mm.
    TempDir dir;
    fpp::Image<float> xyz(160, 120, 3);
    for (int y = 0; y < 120; ++y) {
        for (int x = 0; x < 160; ++x) {
            xyz.at(x, y, 0) = 0.37f * static_cast<float>(x) - 30.0f;
            xyz.at(x, y, 1) = -0.41f * static_cast<float>(y) + 20.0f;
            xyz.at(x, y, 2) = 500.0f + 0.0123f * static_cast<float>(x * y);
        }
    }
    fpp::write_tiff(dir / "xyz.tiff", xyz);
    EXPECT_EQ(fpp::read_tiff_float(dir / "xyz.tiff").storage(), xyz.storage());
}

TEST(ImageIo, ReadsBigEndianFloatTiffFixture) {
    const fpp::Image<float> image = fpp::read_tiff_float(fixture("float32_be_2x2.tiff"));
    ASSERT_EQ(image.size(), (fpp::Size{2, 2}));
    ASSERT_EQ(image.channels(), 1);
    EXPECT_EQ(image.at(0, 0), 1.5f);
    EXPECT_EQ(image.at(1, 0), -2.25f);
    EXPECT_EQ(bits_of(image.at(0, 1)), 0x7fc00001u);
    EXPECT_EQ(image.at(1, 1), std::numeric_limits<float>::infinity());
}

TEST(ImageIo, TiffReaderRejectsOtherKindsAndCorruptFiles) {
    expect_input_error_naming(fixture("uint16_2x2.tiff"),
                              [&] { fpp::read_tiff_float(fixture("uint16_2x2.tiff")); });
    expect_input_error_naming(fixture("rgb8_2x2.png"),
                              [&] { fpp::read_tiff_float(fixture("rgb8_2x2.png")); });
    TempDir dir;
    expect_input_error_naming(dir / "none.tiff", [&] { fpp::read_tiff_float(dir / "none.tiff"); });

    fpp::Image<float> image(200, 150, 2, 1.25f);
    fpp::write_tiff(dir / "ok.tiff", image);
    const auto size = fs::file_size(dir / "ok.tiff");
    for (const std::uintmax_t cut : {std::uintmax_t{0}, std::uintmax_t{7}, size / 3, size - 9}) {
        SCOPED_TRACE(cut);
        fs::copy_file(dir / "ok.tiff", dir / "cut.tiff", fs::copy_options::overwrite_existing);
        truncate_file(dir / "cut.tiff", cut);
        expect_input_error_naming(dir / "cut.tiff",
                                  [&] { fpp::read_tiff_float(dir / "cut.tiff"); });
    }
}

// A small TIFF whose header claims a huge image is refused before the
// samples are allocated (found by fuzzing: a few hundred bytes made the
// reader allocate gigabytes).
TEST(ImageIo, TiffClaimingMoreThanItsFileHoldsIsRefused) {
    TempDir dir;
    fpp::write_tiff(dir / "small.tiff", fpp::Image<float>(4, 4, 1, 0.5f));
    std::string bytes = fpp::yaml_fields::read_text_file(dir / "small.tiff");
    ASSERT_EQ(bytes.substr(0, 2), "II");
    const auto u16 = [&](std::size_t at) {
        return static_cast<unsigned>(static_cast<unsigned char>(bytes[at])) |
               static_cast<unsigned>(static_cast<unsigned char>(bytes[at + 1])) << 8;
    };
    const std::size_t ifd = u16(4) | static_cast<std::size_t>(u16(6)) << 16;
    int patched = 0;
    for (unsigned e = 0; e < u16(ifd); ++e) {
        const std::size_t entry = ifd + 2 + 12 * e;
        if (u16(entry) != 256 && u16(entry) != 257) // ImageWidth, ImageLength
            continue;
        // 16384 (0x4000) as a SHORT or the low half of a LONG.
        bytes[entry + 8] = 0x00;
        bytes[entry + 9] = 0x40;
        ++patched;
    }
    ASSERT_EQ(patched, 2);
    std::ofstream(dir / "claims.tiff", std::ios::binary) << bytes;
    ASSERT_LT(fs::file_size(dir / "claims.tiff"), 4096u);
    try {
        fpp::read_tiff_float(dir / "claims.tiff");
        FAIL() << "accepted";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), dir / "claims.tiff");
        EXPECT_NE(std::string(e.what()).find("16384x16384x1"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, TiffWriterRefusesUnsupportedImages) {
    TempDir dir;
    EXPECT_THROW(fpp::write_tiff(dir / "a.tiff", fpp::Image<float>(4, 4, 5)),
                 std::invalid_argument);
    EXPECT_THROW(fpp::write_tiff(dir / "b.tiff", fpp::Image<float>()), std::invalid_argument);
    EXPECT_THROW(fpp::write_tiff(dir / "missing" / "c.tiff", fpp::Image<float>(4, 4, 1)),
                 fpp::IoError);
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(PngRead, HeaderClaimingMoreThanTheFileCanHoldIsRefusedBeforeAllocating) {
    // A 59-byte PNG whose IHDR claims 16000 x 16000 16-bit grey (512 MB).
    std::string png = "\x89PNG\r\n\x1a\n";
    auto be32 = [](std::uint32_t v) {
        std::string s(4, '\0');
        for (int k = 0; k < 4; ++k)
            s[std::size_t(k)] = static_cast<char>(v >> (24 - 8 * k));
        return s;
    };
    auto chunk = [&](const std::string& type, const std::string& data) {
        const std::string body = type + data;
        const auto crc = static_cast<std::uint32_t>(
            crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size())));
        return be32(static_cast<std::uint32_t>(data.size())) + body + be32(crc);
    };
    std::string ihdr = be32(16000) + be32(16000);
    ihdr += std::string("\x10\x00\x00\x00\x00", 5); // 16-bit, grey, deflate, filter 0, no interlace
    png += chunk("IHDR", ihdr);
    png += chunk("IDAT", std::string("\x78\x9c", 2)); // a zlib header, then nothing
    png += chunk("IEND", "");
    TempDir dir;
    const fs::path path = dir / "bomb.png";
    std::ofstream(path, std::ios::binary) << png;
    try {
        fpp::read_png_gray(path);
        ADD_FAILURE() << "accepted";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(std::string(e.what()).find("more than a 59-byte file can hold"),
                  std::string::npos)
            << e.what();
    }
}

// Found while fuzzing (issue 17): the TIFF readers asked fs::exists without an
// error code, so a name the file system cannot look up (longer than NAME_MAX)
// escaped as std::filesystem::filesystem_error instead of InputError naming
// the file. Every frame reader answers such a name with InputError.
TEST(ImageIo, NameTooLongForTheFileSystemIsAnInputError) {
    TempDir dir;
    const fs::path path = dir / (std::string(300, 'a') + ".tiff");
    const auto expect_input_error = [&](const char* reader, auto&& read) {
        try {
            read();
            ADD_FAILURE() << reader << " accepted a missing file";
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), path) << reader;
            EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
        }
    };
    expect_input_error("read_tiff_float", [&] { fpp::read_tiff_float(path); });
    expect_input_error("read_tiff_gray", [&] { fpp::read_tiff_gray(path); });
    expect_input_error("read_tiff_gray_info", [&] { fpp::read_tiff_gray_info(path); });
    expect_input_error("read_png_gray", [&] { fpp::read_png_gray(path); });
    expect_input_error("read_bmp_gray", [&] { fpp::read_bmp_gray(path); });
    expect_input_error("read_frame", [&] { fpp::read_frame(path); });
}
