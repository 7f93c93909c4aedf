#pragma once
// PNG (libpng) and float TIFF (libtiff) reading and writing; camera frames
// read from PNG, TIFF (libtiff) or BMP (our own strict reader). Writers are
// atomic: temporary file, fsync, rename.
//
// Readers throw InputError naming the file for anything that is not the
// expected image (missing, truncated, corrupt, wrong type); writers throw
// IoError for operating-system failures (permission, full disk) and
// std::invalid_argument for an image they cannot represent.

#include "fpp/enum_names.hpp"
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

// Camera frames: 8- or 16-bit single-channel grey images in any format a
// capture set allows.
enum class FrameFileFormat { png, tiff, bmp };
inline constexpr EnumName<FrameFileFormat> kFrameFileFormatNames[] = {
    {FrameFileFormat::png, "PNG"},
    {FrameFileFormat::tiff, "TIFF"},
    {FrameFileFormat::bmp, "BMP"},
};
const char* to_string(FrameFileFormat format); // "PNG", "TIFF", "BMP"
struct FrameInfo {
    FrameFileFormat format = FrameFileFormat::png;
    Size size;
    int bit_depth = 0; // 8 or 16
};
// The format from the file's first bytes (its magic), never its name.
// InputError naming the file when it is none of PNG, TIFF, BMP.
FrameFileFormat frame_file_format(const std::filesystem::path& path);
// The header of a grey frame; InputError naming the file and why for
// anything read_frame would refuse at the header (colour, depth, size, ...).
FrameInfo read_frame_info(const std::filesystem::path& path);
// Reads a grey frame of any of those formats (dispatch on the magic bytes).
Frame read_frame(const std::filesystem::path& path);

// An 8- or 16-bit unsigned single-channel (MinIsBlack) TIFF, strips or tiles,
// any compression libtiff decodes. Anything else is refused naming the file.
Frame read_tiff_gray(const std::filesystem::path& path);
FrameInfo read_tiff_gray_info(const std::filesystem::path& path);
// An uncompressed BMP (BITMAPINFOHEADER or a later header): 8-bit with a grey
// palette, or 24/32-bit whose three colour channels are equal; bottom-up or
// top-down. Colour, compression, truncation and sizes the file cannot hold
// are refused naming the file, before any pixel buffer is allocated.
Frame read_bmp_gray(const std::filesystem::path& path);
FrameInfo read_bmp_gray_info(const std::filesystem::path& path);

// PNG writers: fast zlib level (frames are written during capture and read by
// tests), lossless. 16-bit samples are stored big-endian as PNG requires.
void write_png(const std::filesystem::path& path, const Image<std::uint8_t>& image);  // 1 or 3 ch
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
