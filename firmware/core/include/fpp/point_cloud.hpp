#pragma once
// Organised point clouds (one slot per camera pixel) and their PLY files.
//
// Conventions: camera frame, mm; pixel (column, row) of the camera image.
// A slot without a point holds NaN in X, Y and Z.
//
// write_ply writes binary little-endian PLY 1.0: only the slots with a
// point, in row-major order, each with x y z quality intensity [sigma_z]
// (float) and the index of its camera pixel (uint), the organised size in
// obj_info lines; so the structure survives without NaN vertices, which not
// every viewer filters out.
// Format: firmware/core/formats/point-cloud-ply.md

#include "fpp/image.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fpp {

struct PointCloud {
    Image<float> xyz;       // 3 channels per camera pixel: X, Y, Z (mm), NaN = no point
    Image<float> quality;   // 1 channel, same size, or empty: modulation B (DN)
    Image<float> intensity; // 1 channel, same size, or empty: mean intensity A (DN)
    // 1 channel, same size, or empty (unknown): predicted standard deviation
    // of Z (camera frame, mm) from the camera's noise (fpp/table_kernel.hpp
    // apply_table), NaN where there is no point.
    Image<float> sigma_z;

    Size size() const { return xyz.size(); }
    // Slots whose X, Y and Z are all finite.
    std::size_t count_points() const;
};

// The PLY file as bytes (header and body), as write_ply writes it. `comments`
// become `comment` lines (line breaks are replaced by spaces). Throws
// std::invalid_argument if xyz is not 3-channel, quality, intensity or
// sigma_z is neither empty nor a 1-channel image of xyz's size, or the image
// has more than 2^32 pixels.
std::string encode_ply(const PointCloud& cloud, const std::vector<std::string>& comments = {});

// Writes the bytes of encode_ply(...) atomically (temporary file, fsync,
// rename). Throws IoError on operating-system failures, std::invalid_argument
// as encode_ply.
void write_ply(const std::filesystem::path& path, const PointCloud& cloud,
               const std::vector<std::string>& comments = {});

// The same bytes written straight to `path` (created or truncated) and
// fsynced, with no temporary file: for a file in a folder published whole by
// write_folder_atomically. The body is encoded piece by piece into a small
// buffer as it is written, so no copy of the whole file is ever held and the
// disk works while the rest is encoded. Throws as write_ply.
void write_ply_synced(const std::filesystem::path& path, const PointCloud& cloud,
                      const std::vector<std::string>& comments = {});

// A PLY point set read back: the vertex element's x, y, z and, when present,
// quality, intensity, sigma_z and pixel (empty vectors when absent).
struct PlyPoints {
    Size organised;                    // from obj_info organised_width/height, {0, 0} if absent
    std::vector<std::string> comments; // `comment` lines, without the keyword
    std::vector<float> x, y, z;
    std::vector<float> quality;
    std::vector<float> intensity;
    std::vector<float> sigma_z; // mm
    std::vector<std::uint32_t> pixel;
    std::size_t size() const { return x.size(); }
};

// Reads a binary little-endian PLY whose first element is `vertex` with
// scalar properties (any PLY scalar type, converted). Other elements after it
// are ignored. Throws InputError naming the file for anything else (not PLY,
// other encodings, list properties in `vertex`, no x/y/z, truncated body).
PlyPoints read_ply(const std::filesystem::path& path);

// Drops the points whose predicted sigma_z exceeds `max_sigma_z_mm` (their X,
// Y, Z and sigma_z become NaN) and returns how many were dropped. Points
// whose sigma_z is NaN (unknown) are kept. Throws std::invalid_argument if the
// cloud has no sigma_z (or one of another size) or the limit is not > 0.
std::size_t drop_points_above_sigma(PointCloud& cloud, float max_sigma_z_mm);

} // namespace fpp
