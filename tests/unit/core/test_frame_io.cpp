// Camera frames in PNG, TIFF and BMP (read_frame): dispatch on the magic
// bytes, exact pixel values of grey BMPs (palette, 24/32-bit, bottom-up and
// top-down) and 8/16-bit TIFFs, and named refusals of colour, compression,
// truncation and sizes a tiny file cannot hold.

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>
#include <tiffio.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using fpp::test::TempDir;

namespace {

void put32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
    for (int k = 0; k < 4; ++k)
        b[at + std::size_t(k)] = static_cast<std::uint8_t>(v >> (8 * k));
}
void put16(std::vector<std::uint8_t>& b, std::size_t at, std::uint16_t v) {
    b[at] = static_cast<std::uint8_t>(v);
    b[at + 1] = static_cast<std::uint8_t>(v >> 8);
}

// A BMP built byte by byte from Microsoft's layout. pixel(x, y) gives the
// stored (blue, green, red) for 24/32-bit or the palette index for 8-bit;
// palette[k] = (blue, green, red).
struct BmpSpec {
    int width = 5;
    int height = 3;
    bool top_down = false;
    int bpp = 8;
    std::uint32_t compression = 0;
    std::vector<std::array<std::uint8_t, 3>> palette;
};

template <class PixelFn> std::vector<std::uint8_t> make_bmp(const BmpSpec& s, PixelFn pixel) {
    const std::size_t stride = std::size_t((s.width * s.bpp + 31) / 32 * 4);
    const std::size_t palette_bytes = 4 * s.palette.size();
    const std::size_t offset = 14 + 40 + palette_bytes;
    std::vector<std::uint8_t> b(offset + stride * std::size_t(s.height), 0);
    b[0] = 'B';
    b[1] = 'M';
    put32(b, 2, static_cast<std::uint32_t>(b.size()));
    put32(b, 10, static_cast<std::uint32_t>(offset));
    put32(b, 14, 40);
    put32(b, 18, static_cast<std::uint32_t>(s.width));
    put32(b, 22, static_cast<std::uint32_t>(s.top_down ? -s.height : s.height));
    put16(b, 26, 1);
    put16(b, 28, static_cast<std::uint16_t>(s.bpp));
    put32(b, 30, s.compression);
    put32(b, 46, static_cast<std::uint32_t>(s.palette.size()));
    for (std::size_t k = 0; k < s.palette.size(); ++k) {
        for (std::size_t c = 0; c < 3; ++c)
            b[54 + 4 * k + c] = s.palette[k][c];
    }
    for (int y = 0; y < s.height; ++y) {
        const int stored_row = s.top_down ? y : s.height - 1 - y;
        std::uint8_t* row = b.data() + offset + stride * std::size_t(stored_row);
        for (int x = 0; x < s.width; ++x) {
            const std::array<std::uint8_t, 3> v = pixel(x, y);
            if (s.bpp == 8) {
                row[x] = v[0];
            } else {
                const std::size_t step = std::size_t(s.bpp / 8);
                for (std::size_t c = 0; c < 3; ++c)
                    row[std::size_t(x) * step + c] = v[c];
            }
        }
    }
    return b;
}

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
}

std::uint8_t grey_at(int x, int y) {
    return static_cast<std::uint8_t>(17 * x + 61 * y + 3);
}

// Expects an InputError naming `path` whose message contains `hint`.
template <class F> void expect_refused(F&& f, const fs::path& path, const std::string& hint) {
    try {
        f();
        ADD_FAILURE() << "accepted " << path << "; expected: " << hint;
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), path) << e.what();
        EXPECT_NE(std::string(e.what()).find(hint), std::string::npos) << e.what();
    }
}

// A grey TIFF written with libtiff directly (independent of our reader).
void write_grey_tiff(const fs::path& path, int width, int height, int bits, int channels,
                     std::uint16_t compression, const std::vector<std::uint16_t>& values) {
    TIFF* t = TIFFOpen(path.c_str(), "w");
    ASSERT_NE(t, nullptr);
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, static_cast<std::uint32_t>(width));
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, static_cast<std::uint32_t>(height));
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, static_cast<std::uint16_t>(channels));
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, static_cast<std::uint16_t>(bits));
    TIFFSetField(t, TIFFTAG_PLANARCONFIG, static_cast<std::uint16_t>(PLANARCONFIG_CONTIG));
    TIFFSetField(
        t, TIFFTAG_PHOTOMETRIC,
        static_cast<std::uint16_t>(channels == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK));
    TIFFSetField(t, TIFFTAG_COMPRESSION, compression);
    TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, static_cast<std::uint32_t>(2));
    const std::size_t row_samples = std::size_t(width) * std::size_t(channels);
    std::vector<std::uint8_t> row(row_samples * std::size_t(bits / 8));
    for (int y = 0; y < height; ++y) {
        for (std::size_t i = 0; i < row_samples; ++i) {
            const std::uint16_t v = values[std::size_t(y) * row_samples + i];
            if (bits == 8) {
                row[i] = static_cast<std::uint8_t>(v);
            } else {
                std::memcpy(row.data() + 2 * i, &v, 2);
            }
        }
        ASSERT_EQ(TIFFWriteScanline(t, row.data(), static_cast<std::uint32_t>(y), 0), 1);
    }
    TIFFClose(t);
}

} // namespace

TEST(BmpFrames, EightBitGreyPaletteBottomUpMapsThroughThePalette) {
    TempDir dir;
    BmpSpec s; // 5 wide: 3 bytes of row padding
    for (int k = 0; k < 256; ++k) {
        const auto v = static_cast<std::uint8_t>(255 - k); // not the identity
        s.palette.push_back({v, v, v});
    }
    write_bytes(dir / "f.bmp", make_bmp(s, [](int x, int y) {
                    return std::array<std::uint8_t, 3>{grey_at(x, y), 0, 0};
                }));
    const fpp::Frame f = fpp::read_frame(dir / "f.bmp");
    ASSERT_EQ(f.bit_depth, 8);
    ASSERT_EQ(f.size(), (fpp::Size{5, 3}));
    for (int y = 0; y < 3; ++y) {
        for (int x = 0; x < 5; ++x)
            EXPECT_EQ(f.u8.at(x, y), 255 - grey_at(x, y)) << x << "," << y;
    }
    const fpp::FrameInfo info = fpp::read_frame_info(dir / "f.bmp");
    EXPECT_EQ(info.format, fpp::FrameFileFormat::bmp);
    EXPECT_EQ(info.size, (fpp::Size{5, 3}));
}

TEST(BmpFrames, TwentyFourAndThirtyTwoBitGreyTopDownAndBottomUp) {
    TempDir dir;
    for (const int bpp : {24, 32}) {
        for (const bool top_down : {false, true}) {
            BmpSpec s;
            s.width = 7;
            s.height = 4;
            s.bpp = bpp;
            s.top_down = top_down;
            std::string name = std::to_string(bpp);
            name += top_down ? "t.bmp" : "b.bmp";
            const fs::path path = dir / name;
            write_bytes(path, make_bmp(s, [](int x, int y) {
                            const std::uint8_t v = grey_at(x, y);
                            return std::array<std::uint8_t, 3>{v, v, v};
                        }));
            const fpp::Frame f = fpp::read_frame(path);
            ASSERT_EQ(f.size(), (fpp::Size{7, 4})) << path;
            for (int y = 0; y < 4; ++y) {
                for (int x = 0; x < 7; ++x)
                    EXPECT_EQ(f.u8.at(x, y), grey_at(x, y)) << path;
            }
        }
    }
}

TEST(BmpFrames, DispatchIsOnTheMagicBytesNotTheName) {
    TempDir dir;
    BmpSpec s;
    s.bpp = 24;
    write_bytes(dir / "looks_like.png", make_bmp(s, [](int x, int y) {
                    const std::uint8_t v = grey_at(x, y);
                    return std::array<std::uint8_t, 3>{v, v, v};
                }));
    EXPECT_EQ(fpp::frame_file_format(dir / "looks_like.png"), fpp::FrameFileFormat::bmp);
    EXPECT_EQ(fpp::read_frame(dir / "looks_like.png").u8.at(4, 2), grey_at(4, 2));
    write_bytes(dir / "text.png", {'h', 'e', 'l', 'l', 'o', '\n'});
    expect_refused([&] { fpp::read_frame(dir / "text.png"); }, dir / "text.png",
                   "not a PNG, TIFF or BMP");
    write_bytes(dir / "empty.bmp", {});
    expect_refused([&] { fpp::read_frame(dir / "empty.bmp"); }, dir / "empty.bmp", "empty file");
}

TEST(BmpFrames, RefusesColourCompressionTruncationAndAbsurdSizes) {
    TempDir dir;
    auto grey = [](int x, int y) {
        const std::uint8_t v = grey_at(x, y);
        return std::array<std::uint8_t, 3>{v, v, v};
    };
    {
        BmpSpec s;
        s.bpp = 24;
        const fs::path p = dir / "colour.bmp";
        write_bytes(p, make_bmp(s, [](int x, int y) {
                        return std::array<std::uint8_t, 3>{
                            10, 10, std::uint8_t(x == 3 && y == 1 ? 11 : 10)};
                    }));
        expect_refused([&] { fpp::read_frame(p); }, p, "pixel (3, 1) is (R 11, G 10, B 10)");
    }
    {
        BmpSpec s;
        s.palette = {{0, 0, 0}, {0, 0, 255}};
        const fs::path p = dir / "palette.bmp";
        write_bytes(p, make_bmp(s, [](int, int) { return std::array<std::uint8_t, 3>{0, 0, 0}; }));
        expect_refused([&] { fpp::read_frame_info(p); }, p, "palette entry 1 is (R 255, G 0, B 0)");
    }
    {
        BmpSpec s;
        s.bpp = 24;
        s.compression = 1;
        const fs::path p = dir / "rle.bmp";
        write_bytes(p, make_bmp(s, grey));
        expect_refused([&] { fpp::read_frame(p); }, p, "compression 1 (RLE8)");
    }
    {
        BmpSpec s;
        s.bpp = 24;
        auto bytes = make_bmp(s, grey);
        bytes.resize(bytes.size() - 5);
        const fs::path p = dir / "cut.bmp";
        write_bytes(p, bytes);
        expect_refused([&] { fpp::read_frame_info(p); }, p, "truncated BMP");
        bytes.resize(30);
        write_bytes(p, bytes);
        expect_refused([&] { fpp::read_frame(p); }, p, "truncated BMP");
    }
    {
        // A 60-byte file claiming 16000 x 16000 (256 M pixels, 768 MB) and
        // one claiming 60000 x 60000: refused from the header alone.
        BmpSpec s;
        s.width = 1;
        s.height = 1;
        s.bpp = 24;
        auto bytes = make_bmp(s, grey);
        const fs::path p = dir / "bomb.bmp";
        put32(bytes, 18, 16000);
        put32(bytes, 22, 16000);
        write_bytes(p, bytes);
        expect_refused([&] { fpp::read_frame(p); }, p, "truncated BMP");
        put32(bytes, 18, 60000);
        put32(bytes, 22, 60000);
        write_bytes(p, bytes);
        expect_refused([&] { fpp::read_frame(p); }, p, "implausible BMP size");
    }
    {
        BmpSpec s;
        s.bpp = 16;
        const fs::path p = dir / "bpp16.bmp";
        write_bytes(p, make_bmp(s, grey));
        expect_refused([&] { fpp::read_frame(p); }, p, "16 bits per pixel");
    }
}

TEST(TiffFrames, EightAndSixteenBitGreyReadExactly) {
    TempDir dir;
    const int w = 9, h = 5;
    for (const int bits : {8, 16}) {
        for (const std::uint16_t compression :
             {std::uint16_t(COMPRESSION_NONE), std::uint16_t(COMPRESSION_ADOBE_DEFLATE)}) {
            std::vector<std::uint16_t> values(std::size_t(w * h));
            for (std::size_t i = 0; i < values.size(); ++i) {
                values[i] =
                    static_cast<std::uint16_t>(bits == 8 ? (i * 37) % 256 : (i * 4093) % 65536);
            }
            std::string name = std::to_string(bits);
            name += "_";
            name += std::to_string(compression);
            name += ".tif";
            const fs::path p = dir / name;
            write_grey_tiff(p, w, h, bits, 1, compression, values);
            const fpp::Frame f = fpp::read_frame(p);
            ASSERT_EQ(f.bit_depth, bits) << p;
            ASSERT_EQ(f.size(), (fpp::Size{w, h}));
            for (int y = 0; y < h; ++y) {
                for (int x = 0; x < w; ++x) {
                    const std::uint16_t want = values[std::size_t(y * w + x)];
                    EXPECT_EQ(bits == 8 ? f.u8.at(x, y) : f.u16.at(x, y), want)
                        << p << x << "," << y;
                }
            }
            EXPECT_EQ(fpp::read_frame_info(p).format, fpp::FrameFileFormat::tiff);
        }
    }
}

TEST(TiffFrames, RefusesColourAndFloatNamingTheFile) {
    TempDir dir;
    const fs::path rgb = dir / "rgb.tif";
    write_grey_tiff(rgb, 4, 3, 8, 3, COMPRESSION_NONE, std::vector<std::uint16_t>(36, 7));
    expect_refused([&] { fpp::read_frame(rgb); }, rgb, "3 samples per pixel");
    const fs::path flt = dir / "float.tif";
    fpp::write_tiff(flt, fpp::Image<float>(4, 3, 1, 0.5f));
    expect_refused([&] { fpp::read_frame_info(flt); }, flt, "8- or 16-bit unsigned");
}

TEST(BmpFrames, MutatedHeadersGiveNamedErrorsOnly) {
    TempDir dir;
    BmpSpec s;
    s.width = 6;
    s.height = 4;
    for (int k = 0; k < 256; ++k) {
        const auto v = static_cast<std::uint8_t>(k);
        s.palette.push_back({v, v, v});
    }
    const auto valid = make_bmp(s, [](int x, int y) {
        return std::array<std::uint8_t, 3>{grey_at(x, y), 0, 0};
    });
    const fs::path p = dir / "m.bmp";
    std::uint32_t state = 777;
    auto next = [&state] {
        state = state * 1664525u + 1013904223u;
        return state >> 8;
    };
    for (int trial = 0; trial < 2000; ++trial) {
        auto bytes = valid;
        // Mutate the headers (first 54 bytes) and sometimes the length.
        for (int e = 0; e < 1 + static_cast<int>(next() % 3); ++e) {
            bytes[next() % 54] = static_cast<std::uint8_t>(next());
        }
        if (next() % 4 == 0)
            bytes.resize(next() % bytes.size());
        write_bytes(p, bytes);
        try {
            const fpp::Frame f = fpp::read_frame(p);
            EXPECT_LE(f.u8.pixel_count(), std::size_t{1} << 28);
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), p);
        } catch (const std::exception& e) {
            ADD_FAILURE() << "unnamed error: " << e.what();
        }
    }
}

TEST(BmpFrames, OpenCvWrittenFixturesReadExactly) {
    const fs::path dir = fpp::test::source_dir() / "tests" / "data" / "frame_io";
    for (const char* name : {"opencv_grey8_5x3.bmp", "opencv_bgr24_5x3.bmp"}) {
        const fpp::Frame f = fpp::read_frame(dir / name);
        ASSERT_EQ(f.bit_depth, 8) << name;
        ASSERT_EQ(f.size(), (fpp::Size{5, 3})) << name;
        for (int y = 0; y < 3; ++y) {
            for (int x = 0; x < 5; ++x)
                EXPECT_EQ(f.u8.at(x, y), grey_at(x, y)) << name << x << y;
        }
    }
    expect_refused([&] { fpp::read_frame(dir / "opencv_colour24_5x3.bmp"); },
                   dir / "opencv_colour24_5x3.bmp", "pixel (2, 1) is (R 200");
}
