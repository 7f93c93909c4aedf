// The coefficient table in memory and its file (.fpt, version 2): a
// 128-byte header with its CRC-32, a CRC-32 per tile, then the float32
// coefficients tile by tile, 4096-byte aligned so a mapped file is used in
// place. load_table refuses anything that does not match the format exactly.
// Format: firmware/core/formats/coefficient-table.md

#include "fpp/coefficient_table.hpp"

#include "crc32.hpp"
#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/unique_fd.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fpp {

// Coefficients are stored and mapped as native floats.
static_assert(std::endian::native == std::endian::little,
              "the .fpt coefficients are little-endian float32; add byte swapping for this host");
static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4);

namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'F', 'P', 'P', 'T', 'A', 'B', 'L', 'E'};
// Version 2 adds the calibration's predicted trueness (bytes 104..119),
// which version 1 keeps zero; both are read.
constexpr std::uint32_t kVersion = 2;
constexpr std::uint32_t kOldestVersion = 1;
constexpr std::size_t kTruenessOffset = 104;
constexpr std::uint32_t kHeaderSize = 128;
constexpr std::size_t kHeaderCrcOffset = 124;
constexpr std::uint32_t kPhaseUnitProjectorPixels = 1;
constexpr std::uint64_t kDataAlignment = 4096;
constexpr int kMaxImageSide = 65535;
constexpr int kTileStep = 8;
constexpr int kMaxTileSide = 256;
constexpr std::size_t kBlockAlignment = 64;

struct Problem {
    std::string field;
    std::string message;
};

std::optional<Problem> check_side(const char* field, int value, int max) {
    if (value < 1 || value > max)
        return Problem{field, "must be in 1.." + std::to_string(max) + " (it is " +
                                  std::to_string(value) + ")"};
    return std::nullopt;
}

std::optional<Problem> check_tile_side(const char* field, int value) {
    if (value < kTileStep || value > kMaxTileSide || value % kTileStep != 0)
        return Problem{field,
                       "must be a multiple of 8 in 8..256 (it is " + std::to_string(value) + ")"};
    return std::nullopt;
}

bool valid_model(TableModel model) {
    return model == TableModel::polynomial || model == TableModel::ray ||
           model == TableModel::rational;
}

// The first thing wrong with a table layout, if any.
std::optional<Problem> check_info(const TableInfo& info) {
    if (auto p = check_side("camera_width", info.camera.width, kMaxImageSide))
        return p;
    if (auto p = check_side("camera_height", info.camera.height, kMaxImageSide))
        return p;
    if (auto p = check_tile_side("tile_width", info.tile_width))
        return p;
    if (auto p = check_tile_side("tile_height", info.tile_height))
        return p;
    if (!valid_model(info.model))
        return Problem{"model", "must be 1 (polynomial), 2 (ray) or 3 (rational) (it is " +
                                    std::to_string(static_cast<std::uint32_t>(info.model)) + ")"};
    if (info.phase_axis != Axis::x && info.phase_axis != Axis::y)
        return Problem{"phase_axis", "must be x or y"};
    if (auto p = check_side("projector_width", info.projector.width, kMaxImageSide))
        return p;
    if (auto p = check_side("projector_height", info.projector.height, kMaxImageSide))
        return p;
    const TableTrueness& t = info.trueness;
    const std::pair<const char*, float> trueness[] = {{"trueness_length_mm", t.length_mm},
                                                      {"trueness_depth_mm", t.depth_mm},
                                                      {"trueness_along_depth_mm", t.along_depth_mm},
                                                      {"trueness_across_mm", t.across_mm}};
    for (const auto& [field, value] : trueness)
        if (!std::isfinite(value) || value < 0)
            return Problem{field, "must be a finite length >= 0 (mm)"};
    if (t.length_mm == 0 && (t.depth_mm != 0 || t.along_depth_mm != 0 || t.across_mm != 0))
        return Problem{"trueness_length_mm",
                       "is 0 (unknown) but the other trueness fields are not"};
    if (t.length_mm > 0 && !(t.depth_mm > 0))
        return Problem{"trueness_depth_mm", "must be positive when the trueness is known"};
    return std::nullopt;
}

// Where everything lies in the file of a (valid) layout.
struct FileLayout {
    std::uint64_t tile_count = 0;
    std::uint64_t tile_bytes = 0;
    std::uint64_t crc_table_offset = kHeaderSize;
    std::uint64_t data_offset = 0;
    std::uint64_t file_size = 0;
};

FileLayout file_layout(const TableInfo& info) {
    FileLayout l;
    l.tile_count = static_cast<std::uint64_t>(info.tile_count());
    l.tile_bytes = static_cast<std::uint64_t>(table_planes(info.model)) *
                   static_cast<std::uint64_t>(info.tile_pixels()) * sizeof(float);
    const std::uint64_t crc_end = l.crc_table_offset + 4 * l.tile_count + 4;
    l.data_offset = (crc_end + kDataAlignment - 1) / kDataAlignment * kDataAlignment;
    l.file_size = l.data_offset + l.tile_count * l.tile_bytes;
    return l;
}

void put_u32(unsigned char* out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        out[i] = static_cast<unsigned char>(v >> (8 * i));
}
void put_u64(unsigned char* out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i)
        out[i] = static_cast<unsigned char>(v >> (8 * i));
}
std::uint32_t get_u32(const unsigned char* in) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i)
        v = (v << 8) | in[i];
    return v;
}
std::uint64_t get_u64(const unsigned char* in) {
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i)
        v = (v << 8) | in[i];
    return v;
}

std::string hex32(std::uint32_t v) {
    static const char digits[] = "0123456789abcdef";
    std::string s = "0x00000000";
    for (int i = 0; i < 8; ++i)
        s[9 - static_cast<std::size_t>(i)] = digits[(v >> (4 * i)) & 0xFu];
    return s;
}

// The first pixel of a tile whose planes break the model rules (see the
// format document), as "pixel (x, y): ..." in camera pixels, or "".
std::string tile_value_problem(const float* tile, const TableInfo& info, int planes, int tx,
                               int ty) {
    const int tp = info.tile_pixels();
    for (int i = 0; i < tp; ++i) {
        const float centre = tile[table_plane::centre * tp + i];
        if (std::isnan(centre))
            continue; // no model
        std::string what;
        const float ihr = tile[table_plane::inv_half_range * tp + i];
        if (!std::isfinite(centre)) {
            what = "centre is infinite";
        } else if (!std::isfinite(ihr) || !(ihr > 0.0f)) {
            what = "inv_half_range is " + std::to_string(ihr) + " (must be finite and > 0)";
        } else {
            for (int k = table_plane::inv_half_range + 1; k < planes; ++k) {
                if (!std::isfinite(tile[k * tp + i])) {
                    what = "coefficient plane " + std::to_string(k) + " is not finite";
                    break;
                }
            }
            // The denominator 1 + d t must not vanish for |t| <= 1.
            const float d = tile[table_plane::rational_d * tp + i];
            if (what.empty() && info.model == TableModel::rational && !(std::fabs(d) < 1.0f))
                what = "pole coefficient d is " + std::to_string(d) + " (|d| must be < 1)";
        }
        if (!what.empty()) {
            const int x = tx * info.tile_width + i % info.tile_width;
            const int y = ty * info.tile_height + i / info.tile_width;
            return "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                   ") has a model (finite centre) but its " + what;
        }
    }
    return {};
}

// Reads exactly `size` bytes at `offset`; a short file is an InputError (it
// may have shrunk since it was measured).
void read_all(int fd, const fs::path& path, std::uint64_t offset, void* data, std::size_t size) {
    auto* p = static_cast<char*>(data);
    while (size > 0) {
        const ssize_t n = ::pread(fd, p, size, static_cast<off_t>(offset));
        if (n < 0) {
            if (errno == EINTR)
                continue;
            throw IoError(path, describe_errno("read failed", errno));
        }
        if (n == 0)
            throw InputError(path, "file size (truncated)", "the file ended early");
        p += n;
        offset += static_cast<std::uint64_t>(n);
        size -= static_cast<std::size_t>(n);
    }
}

float* allocate_block(std::size_t floats) {
    return static_cast<float*>(
        ::operator new[](floats * sizeof(float), std::align_val_t{kBlockAlignment}));
}

// The header bytes of a table (header_crc included).
std::vector<unsigned char> encode_header(const TableInfo& info, const FileLayout& l) {
    std::vector<unsigned char> h(kHeaderSize, 0);
    unsigned char* b = h.data();
    std::memcpy(b, kMagic, sizeof kMagic);
    put_u32(b + 8, kVersion);
    put_u32(b + 12, kHeaderSize);
    put_u32(b + 16, static_cast<std::uint32_t>(info.camera.width));
    put_u32(b + 20, static_cast<std::uint32_t>(info.camera.height));
    put_u32(b + 24, static_cast<std::uint32_t>(info.tile_width));
    put_u32(b + 28, static_cast<std::uint32_t>(info.tile_height));
    put_u32(b + 32, static_cast<std::uint32_t>(info.model));
    put_u32(b + 36, static_cast<std::uint32_t>(table_planes(info.model)));
    put_u32(b + 40, info.phase_axis == Axis::x ? 0u : 1u);
    put_u32(b + 44, static_cast<std::uint32_t>(info.projector.width));
    put_u32(b + 48, static_cast<std::uint32_t>(info.projector.height));
    put_u32(b + 52, kPhaseUnitProjectorPixels);
    put_u64(b + 56, info.calibration_hash);
    put_u64(b + 64, static_cast<std::uint64_t>(info.created_unix_s));
    put_u32(b + 72, static_cast<std::uint32_t>(info.tiles_x()));
    put_u32(b + 76, static_cast<std::uint32_t>(info.tiles_y()));
    put_u32(b + 80, static_cast<std::uint32_t>(l.tile_count));
    put_u32(b + 84, static_cast<std::uint32_t>(l.tile_bytes));
    put_u64(b + 88, l.crc_table_offset);
    put_u64(b + 96, l.data_offset);
    const float trueness[4] = {info.trueness.length_mm, info.trueness.depth_mm,
                               info.trueness.along_depth_mm, info.trueness.across_mm};
    for (int k = 0; k < 4; ++k)
        put_u32(b + kTruenessOffset + 4 * k, std::bit_cast<std::uint32_t>(trueness[k]));
    put_u32(b + kHeaderCrcOffset, crc32(b, kHeaderCrcOffset));
    return h;
}

// Decodes and checks a header whose magic, version and CRC have been checked.
TableInfo decode_header(const fs::path& path, const unsigned char* b, std::uint32_t version) {
    auto fail = [&](const std::string& field, const std::string& message) {
        throw InputError(path, field, message);
    };
    auto as_int = [&](const char* field, std::uint32_t v) {
        if (v > static_cast<std::uint32_t>(std::numeric_limits<int>::max()))
            fail(field, "out of range (" + std::to_string(v) + ")");
        return static_cast<int>(v);
    };
    TableInfo info;
    info.camera = {as_int("camera_width", get_u32(b + 16)),
                   as_int("camera_height", get_u32(b + 20))};
    info.tile_width = as_int("tile_width", get_u32(b + 24));
    info.tile_height = as_int("tile_height", get_u32(b + 28));
    const std::uint32_t model = get_u32(b + 32);
    info.model = static_cast<TableModel>(model);
    const std::uint32_t axis = get_u32(b + 40);
    if (axis > 1)
        fail("phase_axis", "must be 0 (x) or 1 (y) (it is " + std::to_string(axis) + ")");
    info.phase_axis = axis == 0 ? Axis::x : Axis::y;
    info.projector = {as_int("projector_width", get_u32(b + 44)),
                      as_int("projector_height", get_u32(b + 48))};
    info.calibration_hash = get_u64(b + 56);
    info.created_unix_s = static_cast<std::int64_t>(get_u64(b + 64));
    if (version >= 2) {
        const auto f32 = [&](int k) {
            return std::bit_cast<float>(get_u32(b + kTruenessOffset + 4 * std::size_t(k)));
        };
        info.trueness = {f32(0), f32(1), f32(2), f32(3)};
    }
    if (auto p = check_info(info))
        fail(p->field, p->message);

    const std::uint32_t planes = get_u32(b + 36);
    if (planes != static_cast<std::uint32_t>(table_planes(info.model)))
        fail("planes", "is " + std::to_string(planes) + " but the " + to_string(info.model) +
                           " model has " + std::to_string(table_planes(info.model)));
    const std::uint32_t unit = get_u32(b + 52);
    if (unit != kPhaseUnitProjectorPixels)
        fail("phase_unit", "unknown code " + std::to_string(unit) +
                               " (the format knows only 1 = projector pixels)");
    const FileLayout l = file_layout(info);
    auto expect = [&](const char* field, std::uint64_t stored, std::uint64_t wanted) {
        if (stored != wanted)
            fail(field,
                 "is " + std::to_string(stored) + ", the layout implies " + std::to_string(wanted));
    };
    expect("tiles_x", get_u32(b + 72), static_cast<std::uint64_t>(info.tiles_x()));
    expect("tiles_y", get_u32(b + 76), static_cast<std::uint64_t>(info.tiles_y()));
    expect("tile_count", get_u32(b + 80), l.tile_count);
    expect("tile_bytes", get_u32(b + 84), l.tile_bytes);
    expect("crc_table_offset", get_u64(b + 88), l.crc_table_offset);
    expect("data_offset", get_u64(b + 96), l.data_offset);
    // Version 1: bytes 104..123 reserved. Version 2: the trueness, then 4
    // reserved bytes.
    const std::size_t reserved = version == 1 ? kTruenessOffset : kTruenessOffset + 16;
    for (std::size_t i = reserved; i < kHeaderCrcOffset; ++i)
        if (b[i] != 0)
            fail("reserved", "bytes " + std::to_string(reserved) + "..123 must be zero");
    return info;
}

} // namespace

const char* to_string(TableModel model) {
    return name_of(kTableModelNames, model, "unknown");
}

TableModel parse_table_model(const std::string& name) {
    return parse_name(kTableModelNames, "table model", name, " or ");
}

int table_planes(TableModel model) {
    switch (model) {
    case TableModel::polynomial:
        return 14;
    case TableModel::ray:
        return 8;
    case TableModel::rational:
        return 9;
    }
    throw std::invalid_argument("unknown table model " +
                                std::to_string(static_cast<std::uint32_t>(model)));
}

void CoefficientTable::AlignedFree::operator()(float* p) const noexcept {
    ::operator delete[](p, std::align_val_t{kBlockAlignment});
}

void CoefficientTable::set_provenance(std::uint64_t calibration_hash,
                                      const TableTrueness& trueness) {
    TableInfo info = info_;
    info.calibration_hash = calibration_hash;
    info.trueness = trueness;
    if (auto p = check_info(info))
        throw std::invalid_argument("coefficient table: " + p->field + ": " + p->message);
    info_ = info;
}

CoefficientTable::CoefficientTable(const TableInfo& info) : info_(info) {
    if (auto p = check_info(info))
        throw std::invalid_argument("coefficient table: " + p->field + " " + p->message);
    planes_ = table_planes(info.model);
    const std::size_t tp = static_cast<std::size_t>(info.tile_pixels());
    const std::size_t tiles = static_cast<std::size_t>(info.tile_count());
    owned_.reset(allocate_block(tiles * static_cast<std::size_t>(planes_) * tp));
    float* d = owned_.get();
    for (std::size_t t = 0; t < tiles; ++t) {
        float* tile = d + t * static_cast<std::size_t>(planes_) * tp;
        std::fill(tile, tile + tp, std::numeric_limits<float>::quiet_NaN());
        std::fill(tile + tp, tile + static_cast<std::size_t>(planes_) * tp, 0.0f);
    }
    data_ = d;
}

CoefficientTable::~CoefficientTable() = default;

CoefficientTable::CoefficientTable(CoefficientTable&& other) noexcept
    : info_(std::exchange(other.info_, TableInfo{})), planes_(std::exchange(other.planes_, 0)),
      data_(std::exchange(other.data_, nullptr)), owned_(std::move(other.owned_)),
      mapping_(std::move(other.mapping_)), mapped_(std::exchange(other.mapped_, false)) {}

CoefficientTable& CoefficientTable::operator=(CoefficientTable&& other) noexcept {
    if (this != &other) {
        info_ = std::exchange(other.info_, TableInfo{});
        planes_ = std::exchange(other.planes_, 0);
        data_ = std::exchange(other.data_, nullptr);
        owned_ = std::move(other.owned_);
        mapping_ = std::move(other.mapping_);
        mapped_ = std::exchange(other.mapped_, false);
    }
    return *this;
}

std::size_t CoefficientTable::index(int plane, int x, int y) const {
    if (plane < 0 || plane >= planes_ || x < 0 || x >= info_.camera.width || y < 0 ||
        y >= info_.camera.height)
        throw std::out_of_range("coefficient table: plane " + std::to_string(plane) + " pixel (" +
                                std::to_string(x) + ", " + std::to_string(y) +
                                ") outside the table");
    const int tx = x / info_.tile_width;
    const int ty = y / info_.tile_height;
    const std::size_t tp = static_cast<std::size_t>(info_.tile_pixels());
    const std::size_t tile =
        static_cast<std::size_t>(ty) * static_cast<std::size_t>(info_.tiles_x()) +
        static_cast<std::size_t>(tx);
    return (tile * static_cast<std::size_t>(planes_) + static_cast<std::size_t>(plane)) * tp +
           static_cast<std::size_t>((y - ty * info_.tile_height) * info_.tile_width +
                                    (x - tx * info_.tile_width));
}

float CoefficientTable::get(int plane, int x, int y) const {
    return data_[index(plane, x, y)];
}

void CoefficientTable::set(int plane, int x, int y, float value) {
    const std::size_t i = index(plane, x, y);
    writable()[i] = value;
}

bool CoefficientTable::has_model(int x, int y) const {
    return std::isfinite(get(table_plane::centre, x, y));
}

const float* CoefficientTable::tile(int tx, int ty) const {
    assert(tx >= 0 && tx < info_.tiles_x() && ty >= 0 && ty < info_.tiles_y());
    const std::size_t tile =
        static_cast<std::size_t>(ty) * static_cast<std::size_t>(info_.tiles_x()) +
        static_cast<std::size_t>(tx);
    return data_ +
           tile * static_cast<std::size_t>(planes_) * static_cast<std::size_t>(info_.tile_pixels());
}

float* CoefficientTable::writable() {
    if (mapped_)
        throw std::logic_error("coefficient table: a memory-mapped table is read-only");
    return owned_.get();
}

void write_table(const std::filesystem::path& path, const CoefficientTable& table) {
    if (table.empty())
        throw std::invalid_argument("write_table: empty coefficient table");
    const TableInfo& info = table.info();
    const FileLayout l = file_layout(info);
    const std::size_t tile_floats = static_cast<std::size_t>(l.tile_bytes / sizeof(float));

    // Everything before the tiles: header, tile CRCs, their CRC, zero padding.
    std::vector<unsigned char> prefix = encode_header(info, l);
    prefix.resize(static_cast<std::size_t>(l.data_offset), 0);
    unsigned char* crcs = prefix.data() + l.crc_table_offset;
    for (int ty = 0; ty < info.tiles_y(); ++ty) {
        for (int tx = 0; tx < info.tiles_x(); ++tx) {
            const float* tile = table.tile(tx, ty);
            // The loader rejects such a file: refuse to write it.
            const std::string problem = tile_value_problem(tile, info, table.planes(), tx, ty);
            if (!problem.empty())
                throw std::invalid_argument("write_table: " + path.string() + ": " + problem);
            const std::size_t i = static_cast<std::size_t>(ty * info.tiles_x() + tx);
            put_u32(crcs + 4 * i, crc32(tile, static_cast<std::size_t>(l.tile_bytes)));
        }
    }
    const std::size_t crc_bytes = static_cast<std::size_t>(4 * l.tile_count);
    put_u32(crcs + crc_bytes, crc32(crcs, crc_bytes));

    const float* data = table.tile(0, 0);
    const std::size_t data_bytes =
        static_cast<std::size_t>(l.tile_count) * tile_floats * sizeof(float);
    write_atomically(path, [&](const fs::path& temp) {
        SyncedFileWriter out(temp);
        out.write({reinterpret_cast<const char*>(prefix.data()), prefix.size()});
        out.write({reinterpret_cast<const char*>(data), data_bytes});
        out.finish();
    });
}

CoefficientTable load_table(const std::filesystem::path& path, const Size* expected_camera,
                            bool map) {
    UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (fd.get() < 0)
        throw IoError(path, describe_errno("cannot open", errno));
    struct stat st {};
    if (::fstat(fd.get(), &st) != 0)
        throw IoError(path, describe_errno("cannot stat", errno));
    if (!S_ISREG(st.st_mode))
        throw InputError(path, "", "not a regular file");
    const auto size = static_cast<std::uint64_t>(st.st_size);

    // Magic and version come first: a later version may lay out the rest differently.
    unsigned char header[kHeaderSize] = {};
    read_all(fd.get(), path, 0, header,
             static_cast<std::size_t>(std::min<std::uint64_t>(size, kHeaderSize)));
    if (size < sizeof kMagic)
        throw InputError(path, "magic",
                         "too short to be a coefficient table (" + std::to_string(size) +
                             " bytes)");
    if (std::memcmp(header, kMagic, sizeof kMagic) != 0)
        throw InputError(path, "magic",
                         "not a coefficient table (.fpt): it does not start with FPPTABLE");
    if (size < 12)
        throw InputError(path, "file size (truncated)", "the file ends inside the header");
    const std::uint32_t version = get_u32(header + 8);
    if (version < kOldestVersion || version > kVersion)
        throw InputError(path, "version",
                         "unsupported version " + std::to_string(version) +
                             " (this build reads versions " + std::to_string(kOldestVersion) +
                             " to " + std::to_string(kVersion) + ")");
    if (size < kHeaderSize)
        throw InputError(path, "file size (truncated)",
                         "the file ends inside the header (" + std::to_string(size) + " bytes)");
    if (get_u32(header + 12) != kHeaderSize)
        throw InputError(path, "header_size",
                         "is " + std::to_string(get_u32(header + 12)) + ", every version has 128");
    const std::uint32_t stored_header_crc = get_u32(header + kHeaderCrcOffset);
    const std::uint32_t header_crc = crc32(header, kHeaderCrcOffset);
    if (stored_header_crc != header_crc)
        throw InputError(path, "header crc",
                         "CRC-32 mismatch (stored " + hex32(stored_header_crc) + ", computed " +
                             hex32(header_crc) + "): the header is corrupt");
    const TableInfo info = decode_header(path, header, version);
    if (expected_camera && !(*expected_camera == info.camera))
        throw InputError(path, "camera_size",
                         "the table is for a " + std::to_string(info.camera.width) + "x" +
                             std::to_string(info.camera.height) + " camera, expected " +
                             std::to_string(expected_camera->width) + "x" +
                             std::to_string(expected_camera->height));
    const FileLayout l = file_layout(info);
    if (size < l.file_size)
        throw InputError(path, "file size (truncated)",
                         std::to_string(size) + " bytes, the header implies " +
                             std::to_string(l.file_size));
    if (size > l.file_size)
        throw InputError(path, "file size (extra bytes)",
                         std::to_string(size) + " bytes, the header implies " +
                             std::to_string(l.file_size));

    // Tile CRCs, their own CRC, and the zero padding up to the tiles.
    const std::size_t crc_bytes = static_cast<std::size_t>(4 * l.tile_count);
    std::vector<unsigned char> crc_block(
        static_cast<std::size_t>(l.data_offset - l.crc_table_offset));
    read_all(fd.get(), path, l.crc_table_offset, crc_block.data(), crc_block.size());
    const std::uint32_t table_crc = crc32(crc_block.data(), crc_bytes);
    if (get_u32(crc_block.data() + crc_bytes) != table_crc)
        throw InputError(path, "crc table crc",
                         "CRC-32 mismatch (stored " + hex32(get_u32(crc_block.data() + crc_bytes)) +
                             ", computed " + hex32(table_crc) + "): the tile CRC table is corrupt");
    if (std::any_of(crc_block.begin() + static_cast<std::ptrdiff_t>(crc_bytes + 4), crc_block.end(),
                    [](unsigned char c) { return c != 0; }))
        throw InputError(path, "padding",
                         "bytes between the tile CRC table and the tiles must be zero");

    CoefficientTable table;
    table.info_ = info;
    table.planes_ = table_planes(info.model);
    const std::size_t data_bytes = static_cast<std::size_t>(l.tile_count * l.tile_bytes);
    if (map) {
        // The file must not shrink while mapped (access would raise SIGBUS):
        // write_table replaces a file by renaming a new one over it, which
        // leaves an existing mapping on the old file intact.
        void* addr =
            ::mmap(nullptr, static_cast<std::size_t>(size), PROT_READ, MAP_PRIVATE, fd.get(), 0);
        if (addr == MAP_FAILED)
            throw IoError(path, describe_errno("cannot map", errno));
        const auto mapped_size = static_cast<std::size_t>(size);
        table.mapping_ =
            std::shared_ptr<void>(addr, [mapped_size](void* p) { ::munmap(p, mapped_size); });
        // Read once front to back now (the CRCs); the kernel reads it in the same order.
        ::madvise(addr, mapped_size, MADV_WILLNEED);
        table.data_ = static_cast<const float*>(
            static_cast<const void*>(static_cast<const unsigned char*>(addr) + l.data_offset));
        table.mapped_ = true;
    } else {
        table.owned_.reset(allocate_block(data_bytes / sizeof(float)));
        read_all(fd.get(), path, l.data_offset, table.owned_.get(), data_bytes);
        table.data_ = table.owned_.get();
    }

    for (int ty = 0; ty < info.tiles_y(); ++ty) {
        for (int tx = 0; tx < info.tiles_x(); ++tx) {
            const int i = ty * info.tiles_x() + tx;
            const float* tile = table.tile(tx, ty);
            const std::uint32_t stored =
                get_u32(crc_block.data() + 4 * static_cast<std::size_t>(i));
            const std::uint32_t computed = crc32(tile, static_cast<std::size_t>(l.tile_bytes));
            if (stored != computed)
                throw InputError(path, "tile " + std::to_string(i) + " crc",
                                 "CRC-32 mismatch (stored " + hex32(stored) + ", computed " +
                                     hex32(computed) + "): tile (" + std::to_string(tx) + ", " +
                                     std::to_string(ty) + ") of camera pixels x " +
                                     std::to_string(tx * info.tile_width) + ".., y " +
                                     std::to_string(ty * info.tile_height) + ".. is corrupt");
            const std::string problem = tile_value_problem(tile, info, table.planes_, tx, ty);
            if (!problem.empty())
                throw InputError(path, "tile " + std::to_string(i) + " values", problem);
        }
    }
    return table;
}

} // namespace fpp
