#pragma once
// PNG (libpng) and float TIFF (libtiff) reading and writing. Writers are
// atomic: temporary file, fsync, rename.
//
// Readers throw InputError naming the file for anything that is not the
// expected image (missing, truncated, corrupt, wrong type); writers throw
// IoError for operating-system failures (permission, full disk) and
// std::invalid_argument for an image they cannot represent.

#include "fpp/image.hpp"

#include <cstdint>
#include <filesystem>
#include <string>

namespace fpp {

// Reads an 8- or 16-bit single-channel PNG. Throws InputError naming the file.
Frame read_png_gray(const std::filesystem::path& path);
// Reads only the header: size and bit depth, channels. Throws InputError.
struct PngInfo {
    Size size;
    int bit_depth = 0;
    int channels = 0; // samples per pixel as stored: 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA, 1 palette
    bool palette = false;
};
PngInfo read_png_info(const std::filesystem::path& path);

// PNG writers: fast zlib level (frames are written during capture and read by
// tests), lossless. 16-bit samples are stored big-endian as PNG requires.
void write_png(const std::filesystem::path& path, const Image<std::uint8_t>& image); // 1 or 3 ch
void write_png(const std::filesystem::path& path, const Image<std::uint16_t>& image); // 1 ch
void write_png(const std::filesystem::path& path, const Frame& frame);
// The same PNG bytes in memory (a preview served over the network).
std::string encode_png(const Frame& frame);

// Float32 TIFF with 1 to 4 interleaved channels (NaN preserved exactly).
// Lossless Deflate with the floating-point predictor.
void write_tiff(const std::filesystem::path& path, const Image<float>& image);
// Reads a float32 TIFF (1 to 4 channels, strips or tiles, either byte order).
Image<float> read_tiff_float(const std::filesystem::path& path);

// Non-atomic variants: write straight to `path` and fsync it. For files
// inside a folder that is published as a whole (write_folder_atomically);
// on failure a partial file may remain at `path`.
void write_png_synced(const std::filesystem::path& path, const Frame& frame);
void write_tiff_synced(const std::filesystem::path& path, const Image<float>& image);

} // namespace fpp
