// Camera frames in any format a capture set allows, told apart by their
// first bytes (a file named .png that holds a BMP is read as a BMP).

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"

#include <array>
#include <cstdint>
#include <fstream>
#include <string>

namespace fpp {

const char* to_string(FrameFileFormat format) {
    return name_of(kFrameFileFormatNames, format, "PNG");
}

FrameFileFormat frame_file_format(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw InputError(path, "", "cannot open: file not found or not readable");
    std::array<unsigned char, 8> magic{};
    in.read(reinterpret_cast<char*>(magic.data()), magic.size());
    const auto got = static_cast<std::size_t>(in.gcount());
    static constexpr std::array<unsigned char, 8> png = {0x89, 'P',  'N',  'G',
                                                         '\r', '\n', 0x1a, '\n'};
    if (got == 8 && magic == png)
        return FrameFileFormat::png;
    // Classic TIFF (42) and BigTIFF (43), either byte order.
    if (got >= 4 && ((magic[0] == 'I' && magic[1] == 'I' && (magic[2] == 42 || magic[2] == 43) &&
                      magic[3] == 0) ||
                     (magic[0] == 'M' && magic[1] == 'M' && magic[2] == 0 &&
                      (magic[3] == 42 || magic[3] == 43)))) {
        return FrameFileFormat::tiff;
    }
    if (got >= 2 && magic[0] == 'B' && magic[1] == 'M')
        return FrameFileFormat::bmp;
    throw InputError(path, "",
                     got == 0 ? std::string("empty file; frames must be PNG, TIFF or BMP")
                              : std::string("not a PNG, TIFF or BMP file (unknown first bytes)"));
}

FrameInfo read_frame_info(const std::filesystem::path& path) {
    switch (frame_file_format(path)) {
    case FrameFileFormat::tiff:
        return read_tiff_gray_info(path);
    case FrameFileFormat::bmp:
        return read_bmp_gray_info(path);
    case FrameFileFormat::png:
        break;
    }
    const PngInfo png = read_png_info(path);
    if (png.channels != 1 || png.palette || (png.bit_depth != 8 && png.bit_depth != 16)) {
        throw InputError(path, "",
                         "must be an 8- or 16-bit single-channel grey PNG (it has " +
                             std::to_string(png.channels) + " channel(s)" +
                             (png.palette ? ", palette" : "") + ", " +
                             std::to_string(png.bit_depth) + " bits)");
    }
    FrameInfo info;
    info.format = FrameFileFormat::png;
    info.size = png.size;
    info.bit_depth = png.bit_depth;
    return info;
}

Frame read_frame(const std::filesystem::path& path) {
    switch (frame_file_format(path)) {
    case FrameFileFormat::tiff:
        return read_tiff_gray(path);
    case FrameFileFormat::bmp:
        return read_bmp_gray(path);
    case FrameFileFormat::png:
        break;
    }
    return read_png_gray(path);
}

} // namespace fpp
