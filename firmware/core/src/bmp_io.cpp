// A strict reader of grey Windows bitmaps (the frames SLStudio and SLMaster
// save). Layout from Microsoft's BITMAPFILEHEADER / BITMAPINFOHEADER
// documentation: little-endian, rows padded to 4 bytes, bottom-up unless the
// height is negative. Every size is checked against the file's length before
// anything is allocated.

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace fpp {

namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kMaxSide = 65535;
constexpr std::int64_t kMaxPixels = std::int64_t{1} << 28;
constexpr std::size_t kFileHeaderBytes = 14;

std::uint32_t u32_at(const std::uint8_t* p) {
    return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
           std::uint32_t{p[3]} << 24;
}
std::uint16_t u16_at(const std::uint8_t* p) {
    return static_cast<std::uint16_t>(p[0] | p[1] << 8);
}
std::int32_t i32_at(const std::uint8_t* p) {
    return static_cast<std::int32_t>(u32_at(p));
}

struct BmpHeader {
    FrameInfo info;
    int bits_per_pixel = 0; // 8, 24 or 32
    bool top_down = false;
    std::uint32_t data_offset = 0;
    std::size_t row_stride = 0;           // bytes per stored row, padded to 4
    std::array<std::uint8_t, 256> grey{}; // 8-bit: palette index -> grey level
    std::size_t palette_size = 0;
};

std::string compression_name(std::uint32_t c) {
    switch (c) {
    case 1:
        return "1 (RLE8)";
    case 2:
        return "2 (RLE4)";
    case 3:
        return "3 (BI_BITFIELDS)";
    case 4:
        return "4 (JPEG)";
    case 5:
        return "5 (PNG)";
    case 6:
        return "6 (BI_ALPHABITFIELDS)";
    default:
        return std::to_string(c);
    }
}

// Reads and checks the headers (and palette) of `path` from `in`.
BmpHeader read_header(const fs::path& path, std::ifstream& in) {
    auto refuse = [&](const std::string& why) { return InputError(path, "", why); };
    std::error_code ec;
    const std::uint64_t file_bytes = fs::file_size(path, ec);
    if (ec)
        throw refuse("cannot read the file size: " + ec.message());

    std::array<std::uint8_t, kFileHeaderBytes + 124> head{};
    const std::size_t head_bytes =
        static_cast<std::size_t>(std::min<std::uint64_t>(file_bytes, head.size()));
    in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head_bytes));
    if (head_bytes < kFileHeaderBytes + 40 || !in) {
        throw refuse("truncated BMP: " + std::to_string(file_bytes) +
                     " bytes cannot hold the file and info headers (54 bytes)");
    }
    if (head[0] != 'B' || head[1] != 'M')
        throw refuse("not a BMP file (no 'BM' signature)");
    const std::uint8_t* h = head.data() + kFileHeaderBytes;
    const std::uint32_t header_size = u32_at(h);
    if (header_size != 40 && header_size != 52 && header_size != 56 && header_size != 108 &&
        header_size != 124) {
        throw refuse("BMP info header of " + std::to_string(header_size) +
                     " bytes is not supported (BITMAPINFOHEADER 40, V2 52, V3 56, V4 108, V5 124)");
    }
    if (kFileHeaderBytes + header_size > file_bytes) {
        throw refuse("truncated BMP: the info header ends past the file's " +
                     std::to_string(file_bytes) + " bytes");
    }
    const std::int64_t width = i32_at(h + 4);
    const std::int64_t signed_height = i32_at(h + 8);
    const std::uint16_t planes = u16_at(h + 12);
    const std::uint16_t bpp = u16_at(h + 14);
    const std::uint32_t compression = u32_at(h + 16);
    const std::uint32_t colours_used = u32_at(h + 32);

    BmpHeader b;
    b.top_down = signed_height < 0;
    const std::int64_t height = signed_height < 0 ? -signed_height : signed_height;
    if (width <= 0 || height == 0 || width > kMaxSide || height > kMaxSide ||
        width * height > kMaxPixels) {
        throw refuse("implausible BMP size " + std::to_string(width) + "x" +
                     std::to_string(signed_height));
    }
    if (planes != 1)
        throw refuse("BMP with " + std::to_string(planes) + " planes (must be 1)");
    if (compression != 0) {
        throw refuse("compressed BMP (compression " + compression_name(compression) +
                     "); frames must be uncompressed (BI_RGB)");
    }
    if (bpp != 8 && bpp != 24 && bpp != 32) {
        throw refuse("BMP of " + std::to_string(bpp) +
                     " bits per pixel; frames must be 8-bit grey palette, 24- or 32-bit grey");
    }
    b.bits_per_pixel = bpp;
    b.data_offset = u32_at(head.data() + 10);
    b.row_stride = static_cast<std::size_t>((width * bpp + 31) / 32 * 4);
    const std::uint64_t data_end =
        std::uint64_t{b.data_offset} + std::uint64_t{b.row_stride} * std::uint64_t(height);
    if (b.data_offset < kFileHeaderBytes + header_size || data_end > file_bytes) {
        throw refuse("truncated BMP: " + std::to_string(width) + "x" + std::to_string(height) +
                     " pixels at " + std::to_string(bpp) + " bits need bytes " +
                     std::to_string(b.data_offset) + " to " + std::to_string(data_end) +
                     " but the file has " + std::to_string(file_bytes));
    }
    if (bpp == 8) {
        b.palette_size = colours_used == 0 ? 256 : colours_used;
        const std::uint64_t palette_start = kFileHeaderBytes + header_size;
        if (b.palette_size > 256 || palette_start + 4 * b.palette_size > b.data_offset) {
            throw refuse("BMP palette of " + std::to_string(colours_used) +
                         " colours does not fit before the pixel data");
        }
        std::vector<std::uint8_t> palette(4 * b.palette_size);
        in.seekg(static_cast<std::streamoff>(palette_start));
        in.read(reinterpret_cast<char*>(palette.data()),
                static_cast<std::streamsize>(palette.size()));
        if (!in)
            throw refuse("truncated BMP: the palette cannot be read");
        for (std::size_t k = 0; k < b.palette_size; ++k) {
            const std::uint8_t* c = palette.data() + 4 * k; // blue, green, red, reserved
            if (c[0] != c[1] || c[1] != c[2]) {
                throw refuse("colour BMP: palette entry " + std::to_string(k) + " is (R " +
                             std::to_string(c[2]) + ", G " + std::to_string(c[1]) + ", B " +
                             std::to_string(c[0]) + "); frames must be grey");
            }
            b.grey[k] = c[0];
        }
    }
    b.info.format = FrameFileFormat::bmp;
    b.info.size = {static_cast<int>(width), static_cast<int>(height)};
    b.info.bit_depth = 8;
    return b;
}

std::ifstream open_bmp(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw InputError(path, "", "cannot open: file not found or not readable");
    return in;
}

} // namespace

FrameInfo read_bmp_gray_info(const std::filesystem::path& path) {
    std::ifstream in = open_bmp(path);
    return read_header(path, in).info;
}

Frame read_bmp_gray(const std::filesystem::path& path) {
    std::ifstream in = open_bmp(path);
    const BmpHeader b = read_header(path, in);
    const int width = b.info.size.width;
    const int height = b.info.size.height;
    Frame frame;
    frame.bit_depth = 8;
    frame.u8 = Image<std::uint8_t>(b.info.size);
    std::vector<std::uint8_t> stored(b.row_stride);
    in.seekg(static_cast<std::streamoff>(b.data_offset));
    const std::size_t step = static_cast<std::size_t>(b.bits_per_pixel / 8);
    for (int r = 0; r < height; ++r) {
        in.read(reinterpret_cast<char*>(stored.data()),
                static_cast<std::streamsize>(stored.size()));
        if (!in)
            throw InputError(path, "",
                             "truncated BMP: row " + std::to_string(r) + " cannot be read");
        const int y = b.top_down ? r : height - 1 - r;
        std::uint8_t* out = frame.u8.row(y);
        if (step == 1) {
            for (int x = 0; x < width; ++x) {
                const std::uint8_t index = stored[std::size_t(x)];
                if (index >= b.palette_size) {
                    throw InputError(path, "",
                                     "BMP pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                         ") uses palette entry " + std::to_string(index) + " of " +
                                         std::to_string(b.palette_size));
                }
                out[x] = b.grey[index];
            }
            continue;
        }
        for (int x = 0; x < width; ++x) {
            const std::uint8_t* c = stored.data() + std::size_t(x) * step; // blue, green, red
            if (c[0] != c[1] || c[1] != c[2]) {
                throw InputError(path, "",
                                 "colour BMP: pixel (" + std::to_string(x) + ", " +
                                     std::to_string(y) + ") is (R " + std::to_string(c[2]) +
                                     ", G " + std::to_string(c[1]) + ", B " + std::to_string(c[0]) +
                                     "); frames must be grey");
            }
            out[x] = c[0];
        }
    }
    return frame;
}

} // namespace fpp
