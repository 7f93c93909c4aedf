// PLY writing of organised point clouds: exact header, binary layout, only
// valid points with their pixel index, atomic writes, reading back.

#include "test_support.hpp"

#include "fpp/error.hpp"
#include "fpp/point_cloud.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include <sys/resource.h>

namespace {

using fpp::test::TempDir;
namespace fs = std::filesystem;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// 3 x 2 cloud: points at pixels 0, 2, 5; pixel 1 has no point, pixel 3 has a
// NaN in Y only and pixel 4 an infinite Z (neither counts as a point).
fpp::PointCloud small_cloud() {
    fpp::PointCloud c;
    c.xyz = fpp::Image<float>(3, 2, 3, kNaN);
    c.quality = fpp::Image<float>(3, 2, 1, kNaN);
    c.intensity = fpp::Image<float>(3, 2, 1, kNaN);
    auto set = [&](int x, int y, float X, float Y, float Z, float q, float a) {
        c.xyz.at(x, y, 0) = X;
        c.xyz.at(x, y, 1) = Y;
        c.xyz.at(x, y, 2) = Z;
        c.quality.at(x, y) = q;
        c.intensity.at(x, y) = a;
    };
    set(0, 0, 1.5f, -2.25f, 480.125f, 90.0f, 120.5f);
    set(2, 0, -100.0f, 50.0f, 512.0f, 10.0f, 30.0f);
    set(0, 1, 0.0f, kNaN, 500.0f, 1.0f, 1.0f);
    set(1, 1, 1.0f, 1.0f, std::numeric_limits<float>::infinity(), 1.0f, 1.0f);
    set(2, 1, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f);
    return c;
}

const std::string kExpectedHeader = "ply\n"
                                    "format binary_little_endian 1.0\n"
                                    "comment hello\n"
                                    "comment two lines\n"
                                    "obj_info organised_width 3\n"
                                    "obj_info organised_height 2\n"
                                    "element vertex 3\n"
                                    "property float x\n"
                                    "property float y\n"
                                    "property float z\n"
                                    "property float quality\n"
                                    "property float intensity\n"
                                    "property uint pixel\n"
                                    "end_header\n";

float f32_at(const std::string& bytes, std::size_t offset) {
    unsigned char b[4];
    std::memcpy(b, bytes.data() + offset, 4);
    const std::uint32_t u = std::uint32_t(b[0]) | (std::uint32_t(b[1]) << 8) |
                            (std::uint32_t(b[2]) << 16) | (std::uint32_t(b[3]) << 24);
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

std::uint32_t u32_at(const std::string& bytes, std::size_t offset) {
    unsigned char b[4];
    std::memcpy(b, bytes.data() + offset, 4);
    return std::uint32_t(b[0]) | (std::uint32_t(b[1]) << 8) | (std::uint32_t(b[2]) << 16) |
           (std::uint32_t(b[3]) << 24);
}

TEST(PointCloud, CountsOnlyFullyFinitePoints) {
    EXPECT_EQ(small_cloud().count_points(), 3u);
    EXPECT_EQ(fpp::PointCloud{}.count_points(), 0u);
}

TEST(PointCloud, EncodesExactHeaderAndLittleEndianRecords) {
    const std::string bytes = fpp::encode_ply(small_cloud(), {"hello", "two\nlines"});
    ASSERT_GE(bytes.size(), kExpectedHeader.size());
    EXPECT_EQ(bytes.substr(0, kExpectedHeader.size()), kExpectedHeader);
    ASSERT_EQ(bytes.size(), kExpectedHeader.size() + 3 * 24);
    const std::size_t b = kExpectedHeader.size();
    // Point 0: pixel 0.
    EXPECT_EQ(f32_at(bytes, b + 0), 1.5f);
    EXPECT_EQ(f32_at(bytes, b + 4), -2.25f);
    EXPECT_EQ(f32_at(bytes, b + 8), 480.125f);
    EXPECT_EQ(f32_at(bytes, b + 12), 90.0f);
    EXPECT_EQ(f32_at(bytes, b + 16), 120.5f);
    EXPECT_EQ(u32_at(bytes, b + 20), 0u);
    // Point 1: pixel (2, 0) = index 2; point 2: pixel (2, 1) = index 5.
    EXPECT_EQ(f32_at(bytes, b + 24), -100.0f);
    EXPECT_EQ(u32_at(bytes, b + 24 + 20), 2u);
    EXPECT_EQ(f32_at(bytes, b + 48 + 8), 5.0f);
    EXPECT_EQ(f32_at(bytes, b + 48 + 16), 7.0f);
    EXPECT_EQ(u32_at(bytes, b + 48 + 20), 5u);
}

TEST(PointCloud, MissingQualityAndIntensityAreWrittenAsNaN) {
    fpp::PointCloud c = small_cloud();
    c.quality = {};
    c.intensity = {};
    const std::string bytes = fpp::encode_ply(c);
    const std::size_t header = bytes.find("end_header\n") + 11;
    ASSERT_EQ(bytes.size(), header + 3 * 24);
    EXPECT_TRUE(std::isnan(f32_at(bytes, header + 12)));
    EXPECT_TRUE(std::isnan(f32_at(bytes, header + 16)));
    EXPECT_EQ(f32_at(bytes, header + 8), 480.125f);
}

TEST(PointCloud, RejectsInconsistentImages) {
    fpp::PointCloud c = small_cloud();
    c.quality = fpp::Image<float>(2, 2, 1);
    EXPECT_THROW(fpp::encode_ply(c), std::invalid_argument);
    c = small_cloud();
    c.intensity = fpp::Image<float>(3, 2, 2);
    EXPECT_THROW(fpp::encode_ply(c), std::invalid_argument);
    c = small_cloud();
    c.xyz = fpp::Image<float>(3, 2, 2);
    EXPECT_THROW(fpp::encode_ply(c), std::invalid_argument);
}

TEST(PointCloud, WritesAtomicallyAndReadsBack) {
    TempDir dir;
    const fs::path path = dir / "cloud.ply";
    std::ofstream(path) << "old content";
    fpp::write_ply(path, small_cloud(), {"frame: camera, mm"});
    // Only the target remains (no temporary files).
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir.path())) {
        (void)e;
        ++files;
    }
    EXPECT_EQ(files, 1);

    const fpp::PlyPoints p = fpp::read_ply(path);
    EXPECT_EQ(p.organised, (fpp::Size{3, 2}));
    ASSERT_EQ(p.comments.size(), 1u);
    EXPECT_EQ(p.comments[0], "frame: camera, mm");
    ASSERT_EQ(p.size(), 3u);
    ASSERT_EQ(p.pixel.size(), 3u);
    EXPECT_EQ(p.pixel[0], 0u);
    EXPECT_EQ(p.pixel[1], 2u);
    EXPECT_EQ(p.pixel[2], 5u);
    EXPECT_EQ(p.x[1], -100.0f);
    EXPECT_EQ(p.y[0], -2.25f);
    EXPECT_EQ(p.z[2], 5.0f);
    EXPECT_EQ(p.quality[0], 90.0f);
    EXPECT_EQ(p.intensity[2], 7.0f);
}

// A cloud of 401 x 397 slots (159,197) with a hole at every 11th slot of a
// diagonal pattern, so that the writer's 65,536-point pieces end between
// slots; `points` gets the number of points.
fpp::PointCloud large_cloud(std::size_t& points) {
    fpp::PointCloud c;
    const int width = 401, height = 397;
    c.xyz = fpp::Image<float>(width, height, 3, kNaN);
    c.quality = fpp::Image<float>(width, height, 1);
    c.intensity = fpp::Image<float>(width, height, 1);
    points = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            if ((x * 7 + y * 3) % 11 == 0)
                continue;
            c.xyz.at(x, y, 0) = static_cast<float>(x) * 0.5f;
            c.xyz.at(x, y, 1) = static_cast<float>(y) * -0.25f;
            c.xyz.at(x, y, 2) = 400.0f + static_cast<float>(x + y) / 8.0f;
            c.quality.at(x, y) = static_cast<float>(x % 97);
            c.intensity.at(x, y) = static_cast<float>(y % 89);
            ++points;
        }
    return c;
}

// The streamed writer (pieces encoded while earlier ones are written) gives
// the bytes of encode_ply exactly.
TEST(PointCloud, StreamedFileHasTheBytesOfEncodePly) {
    TempDir dir;
    std::size_t points = 0;
    const fpp::PointCloud c = large_cloud(points);
    ASSERT_GT(points, 2u * 65536u);
    const std::string encoded = fpp::encode_ply(c, {"streamed"});
    fpp::write_ply_synced(dir / "streamed.ply", c, {"streamed"});
    std::ifstream in(dir / "streamed.ply", std::ios::binary);
    std::ostringstream file;
    file << in.rdbuf();
    EXPECT_EQ(file.str().size(), encoded.size());
    EXPECT_TRUE(file.str() == encoded);
    EXPECT_EQ(fpp::read_ply(dir / "streamed.ply").size(), points);
}

// A write that fails part-way (here the file-size limit, EFBIG, after the
// header and the first MiB) is an IoError naming the file, from the thread
// that writes in the background too; write_ply leaves nothing behind.
TEST(PointCloud, WriteFailingPartWayIsAnIoErrorNamingTheFile) {
    TempDir dir;
    std::size_t points = 0;
    const fpp::PointCloud c = large_cloud(points);
    rlimit old{};
    ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
    rlimit limited = old;
    limited.rlim_cur = 1u << 20;
    const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
    std::string streamed_error, atomic_error;
    try {
        fpp::write_ply_synced(dir / "streamed.ply", c);
    } catch (const fpp::IoError& e) {
        streamed_error = e.what();
    }
    try {
        fpp::write_ply(dir / "atomic.ply", c);
    } catch (const fpp::IoError& e) {
        atomic_error = e.what();
    }
    ::setrlimit(RLIMIT_FSIZE, &old);
    std::signal(SIGXFSZ, old_handler);
    EXPECT_NE(streamed_error.find("streamed.ply"), std::string::npos) << streamed_error;
    EXPECT_NE(streamed_error.find("write failed"), std::string::npos) << streamed_error;
    EXPECT_NE(atomic_error.find("atomic.ply"), std::string::npos) << atomic_error;
    EXPECT_FALSE(fs::exists(dir / "atomic.ply"));
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir.path()))
        files += e.path().filename() == "streamed.ply" ? 0 : 1;
    EXPECT_EQ(files, 0); // no temporary file left by write_ply
}

TEST(PointCloud, EmptyCloudIsAValidFile) {
    TempDir dir;
    fpp::PointCloud c;
    c.xyz = fpp::Image<float>(4, 3, 3, kNaN);
    fpp::write_ply(dir / "empty.ply", c);
    const fpp::PlyPoints p = fpp::read_ply(dir / "empty.ply");
    EXPECT_EQ(p.size(), 0u);
    EXPECT_EQ(p.organised, (fpp::Size{4, 3}));
}

TEST(PointCloud, ReaderConvertsOtherScalarTypesAndSkipsOtherProperties) {
    TempDir dir;
    std::string bytes = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
                        "property double x\nproperty uchar red\nproperty float y\n"
                        "property short z\nelement face 0\nproperty list uchar int vertex_indices\n"
                        "end_header\n";
    auto put = [&](const void* p, std::size_t n) { bytes.append(static_cast<const char*>(p), n); };
    for (int i = 0; i < 2; ++i) {
        const double x = 1.25 + i;
        const unsigned char red = 7;
        const float y = -3.5f * float(i + 1);
        const std::int16_t z = static_cast<std::int16_t>(400 + i);
        put(&x, 8);
        put(&red, 1);
        put(&y, 4);
        put(&z, 2);
    }
    {
        std::ofstream out(dir / "other.ply", std::ios::binary);
        out << bytes;
    }
    const fpp::PlyPoints p = fpp::read_ply(dir / "other.ply");
    ASSERT_EQ(p.size(), 2u);
    EXPECT_EQ(p.x[1], 2.25f);
    EXPECT_EQ(p.y[1], -7.0f);
    EXPECT_EQ(p.z[0], 400.0f);
    EXPECT_TRUE(p.pixel.empty());
    EXPECT_EQ(p.organised, (fpp::Size{0, 0}));
}

TEST(PointCloud, ReaderRejectsMalformedFilesNamingThem) {
    TempDir dir;
    auto expect_rejected = [&](const std::string& name, const std::string& content,
                               const std::string& needle) {
        const fs::path path = dir / name;
        {
            std::ofstream out(path, std::ios::binary);
            out << content;
        }
        try {
            fpp::read_ply(path);
            ADD_FAILURE() << name << " was accepted";
        } catch (const fpp::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    expect_rejected("notply.ply", "hello\n", "not a PLY");
    expect_rejected("ascii.ply",
                    "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nend_header\n",
                    "binary_little_endian");
    expect_rejected("noxyz.ply",
                    "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
                    "end_header\n",
                    "x, y, z");
    expect_rejected("truncated.ply",
                    "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n0123456789",
                    "truncated");
    expect_rejected("noend.ply", "ply\nformat binary_little_endian 1.0\n", "end_header");
    EXPECT_THROW(fpp::read_ply(dir / "missing.ply"), fpp::InputError);
}

TEST(PointCloud, WriteToMissingFolderIsAnIoErrorAndLeavesNothing) {
    TempDir dir;
    EXPECT_THROW(fpp::write_ply(dir / "no" / "such" / "cloud.ply", small_cloud()), fpp::IoError);
    EXPECT_FALSE(fs::exists(dir / "no"));
}

} // namespace
