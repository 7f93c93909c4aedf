#pragma once
// PNG (libpng) and float TIFF (libtiff) reading and writing. Writers are
// atomic: temporary file, fsync, rename.

#include "fpp/image.hpp"

#include <cstdint>
#include <filesystem>

namespace fpp {

// Reads an 8- or 16-bit single-channel PNG. Throws InputError naming the file.
Frame read_png_gray(const std::filesystem::path& path);
// Reads only the header: size and bit depth, channels. Throws InputError.
struct PngInfo {
    Size size;
    int bit_depth = 0;
    int channels = 0;
};
PngInfo read_png_info(const std::filesystem::path& path);

void write_png(const std::filesystem::path& path, const Image<std::uint8_t>& image); // 1 or 3 ch
void write_png(const std::filesystem::path& path, const Image<std::uint16_t>& image); // 1 ch
void write_png(const std::filesystem::path& path, const Frame& frame);

// Float32 TIFF with 1 to 4 interleaved channels (NaN preserved exactly).
void write_tiff(const std::filesystem::path& path, const Image<float>& image);
Image<float> read_tiff_float(const std::filesystem::path& path);

} // namespace fpp
