#pragma once
// The hybrid model's per-pixel coefficient table, in memory and in its file
// (.fpt), as the host tool writes it and the scanner loads it.
//
// Conventions: camera frame, mm; pixel centres on integers. The phase is the
// decoded projector coordinate along `phase_axis` (projector px, as
// DecodeResult::proj_x), not radians: the two differ by a constant factor.
//
// Per camera pixel the phase p is normalised to t = (p - centre) * inv_half_range,
// where [centre - 1/inv_half_range, centre + 1/inv_half_range] is the phase range
// the pixel was calibrated over; t outside [-1, 1] is outside that range and
// gives no point (the cubic is not extrapolated). A pixel without a model
// (seen in too few poses, badly conditioned) has centre = NaN.
//
// Models (coefficients c0..c3 of c0 + c1 t + c2 t^2 + c3 t^3):
//   polynomial  the paper's: X, Y and Z each a cubic in t (14 planes:
//               centre, inv_half_range, X0..X3, Y0..Y3, Z0..Z3)
//   rational    Z = (Z0 + Z1 t + Z2 t^2 + Z3 t^3) / (1 + d t), X = xn Z,
//               Y = yn Z (9 planes: centre, inv_half_range, Z0..Z3, d, xn,
//               yn). Along a camera ray the projector column of a pinhole
//               projector is a ratio of linear functions of depth, so Z is
//               one of the column: the denominator holds that exactly and the
//               cubic numerator the lens distortion, where a cubic alone
//               leaves about 0.02 mm (0.06 mm at worst) over the paper's
//               130 mm deep volume.
//   ray         Z a cubic in t, X = xn Z and Y = yn Z with the pixel's
//               undistorted camera ray (xn, yn) (8 planes: centre,
//               inv_half_range, Z0..Z3, xn, yn)
//
// Storage: the camera image is cut into tiles of tile_width x tile_height
// pixels (edge tiles padded with centre = NaN); each tile stores its planes
// one after the other, each plane tile_width * tile_height floats in row-major
// order, so a kernel streams a tile with unit-stride loads. The file layout
// (header, per-tile CRC-32, alignment): firmware/core/formats/coefficient-table.md.

#include "fpp/enum_names.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

namespace fpp {

enum class TableModel : std::uint32_t { polynomial = 1, ray = 2, rational = 3 };
inline constexpr EnumName<TableModel> kTableModelNames[] = {
    {TableModel::polynomial, "polynomial"},
    {TableModel::ray, "ray"},
    {TableModel::rational, "rational"},
};

// "polynomial", "ray", "rational"; parse throws std::invalid_argument otherwise.
const char* to_string(TableModel model);
TableModel parse_table_model(const std::string& name);

// Plane indices.
namespace table_plane {
inline constexpr int centre = 0;
inline constexpr int inv_half_range = 1;
inline constexpr int poly_x = 2; // polynomial: X0..X3 at 2..5, Y0..Y3 at 6..9, Z0..Z3 at 10..13
inline constexpr int poly_y = 6;
inline constexpr int poly_z = 10;
inline constexpr int ray_z = 2; // ray: Z0..Z3 at 2..5, xn at 6, yn at 7
inline constexpr int ray_xn = 6;
inline constexpr int ray_yn = 7;
inline constexpr int rational_z = 2; // rational: Z0..Z3 at 2..5, d at 6, xn at 7, yn at 8
inline constexpr int rational_d = 6;
inline constexpr int rational_xn = 7;
inline constexpr int rational_yn = 8;
} // namespace table_plane

// Planes per pixel of a model: 14, 8 or 9.
int table_planes(TableModel model);

// What the calibration's own uncertainty means for lengths (the host tool's
// fpp/calib/trueness.hpp): one sigma of the error of a length_mm length
// centred at depth_mm (camera Z) on the optical axis, along depth and
// across, mm. All 0: unknown (a version-1 table, a calibration made
// elsewhere).
struct TableTrueness {
    float length_mm = 0, depth_mm = 0, along_depth_mm = 0, across_mm = 0;
    bool known() const { return length_mm > 0; }
};

struct TableInfo {
    Size camera;         // camera image the table belongs to
    int tile_width = 32; // pixels; multiples of 8 up to 256
    int tile_height = 8; // pixels; multiples of 8 up to 256
    TableModel model = TableModel::ray;
    Axis phase_axis = Axis::x;
    Size projector;                     // projector image the phase refers to
    std::uint64_t calibration_hash = 0; // FNV-1a 64 of the source calibration file's bytes
    std::int64_t created_unix_s = 0;    // seconds since 1970 (UTC)
    TableTrueness trueness;

    int tiles_x() const { return (camera.width + tile_width - 1) / tile_width; }
    int tiles_y() const { return (camera.height + tile_height - 1) / tile_height; }
    int tile_count() const { return tiles_x() * tiles_y(); }
    int tile_pixels() const { return tile_width * tile_height; }
};

class CoefficientTable {
public:
    CoefficientTable() = default;
    // A table of the given layout, every pixel without a model (centre NaN,
    // other planes 0). Throws std::invalid_argument for a bad layout (sizes
    // not positive, tile size out of range).
    explicit CoefficientTable(const TableInfo& info);
    ~CoefficientTable();
    CoefficientTable(CoefficientTable&&) noexcept;
    CoefficientTable& operator=(CoefficientTable&&) noexcept;

    const TableInfo& info() const { return info_; }
    // What the header says of the calibration the table came from (its
    // file's hash, its predicted trueness), for a calibration whose
    // trueness is known only after the fit; no coefficient changes. Throws
    // std::invalid_argument for a trueness the file cannot hold.
    void set_provenance(std::uint64_t calibration_hash, const TableTrueness& trueness);
    int planes() const { return planes_; }
    bool empty() const { return data_ == nullptr; }
    // Whether the coefficients are a read-only mapping of the file.
    bool mapped() const { return mapped_; }

    // Coefficient `plane` of camera pixel (x, y). The non-const form throws
    // std::logic_error on a mapped (read-only) table.
    float get(int plane, int x, int y) const;
    void set(int plane, int x, int y, float value);
    // Whether pixel (x, y) has a model.
    bool has_model(int x, int y) const;

    // Tile (tx, ty): its first float; plane p starts p * tile_pixels() later.
    const float* tile(int tx, int ty) const;

private:
    friend CoefficientTable load_table(const std::filesystem::path&, const Size*, bool);
    // Frees a 64-byte aligned coefficient block (cache-line aligned tiles).
    struct AlignedFree {
        void operator()(float* p) const noexcept;
    };
    TableInfo info_;
    int planes_ = 0;
    const float* data_ = nullptr;                 // planes of every tile, tile by tile
    std::unique_ptr<float[], AlignedFree> owned_; // when built or read into memory
    std::shared_ptr<void> mapping_;               // when memory-mapped (unmapped on release)
    bool mapped_ = false;
    std::size_t index(int plane, int x, int y) const; // throws std::out_of_range
    float* writable();
};

// Writes the table atomically (temporary file, fsync, rename). Throws IoError,
// and std::invalid_argument (writing nothing) for an empty table or a pixel
// with a model (finite centre) whose inv_half_range is not finite and > 0 or
// whose coefficients are not all finite: load_table would reject that file.
void write_table(const std::filesystem::path& path, const CoefficientTable& table);

// Loads and validates a table file: magic, version, header fields, header
// CRC, file size, every tile's CRC, and, when `expected_camera` is given, the
// camera size. `map` memory-maps the file read-only instead of reading it.
// Throws InputError(file, field, message) naming what is wrong (e.g. field
// "tile 17 crc", "version", "camera_size"), IoError for OS failures.
CoefficientTable load_table(const std::filesystem::path& path,
                            const Size* expected_camera = nullptr, bool map = true);

} // namespace fpp
