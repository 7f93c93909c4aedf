// The organised binary PLY of fpp::write_ply opened by the readers of other
// tools: Open3D (python3-open3d), CloudCompare and MeshLab (their headless
// command lines), each asked to read our file; the points they read must be
// ours, bit for bit, in order, without the slots that hold no point.
//
// Open3D hands its points back as a raw float32 dump (a short script);
// CloudCompare and MeshLab re-save the cloud as binary PLY, read back with
// fpp::read_ply. MeshLab's meshlabserver needs an OpenGL context even to
// convert a file, hence an X server (xvfb-run). Packages: see
// toolchain/install-deps.sh. A missing tool skips its test with a message,
// and fails it in CI (env CI=true), where the tools are installed.

#include "test_support.hpp"

#include "fpp/image.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using fpp::test::TempDir;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Skips (or, in CI, fails) the test when an external tool is missing.
#define FPP_REQUIRE_TOOL(available, what)                                                          \
    do {                                                                                           \
        if (!(available)) {                                                                        \
            if (::fpp::test::in_ci()) {                                                            \
                FAIL() << "missing in CI: " << (what)                                              \
                       << " (toolchain/install-deps.sh installs it)";                              \
            }                                                                                      \
            GTEST_SKIP() << "not installed: " << (what)                                            \
                         << " (toolchain/install-deps.sh installs it)";                            \
        }                                                                                          \
    } while (0)

std::string quoted(const std::string& text) {
    std::string q = "'";
    for (const char c : text)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// Runs a shell command with stdout and stderr into `log`; true on exit 0.
bool run(const std::string& command, const fs::path& log) {
    const std::string line = command + " > " + quoted(log.string()) + " 2>&1";
    return std::system(line.c_str()) == 0;
}

std::string read_text(const fs::path& path) {
    std::error_code error;
    const auto size = fs::file_size(path, error);
    if (error)
        return {};
    std::string text(static_cast<std::size_t>(size), '\0');
    std::ifstream in(path, std::ios::binary);
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    return text;
}

bool on_path(const std::string& program) {
    return std::system(("command -v " + quoted(program) + " > /dev/null 2>&1").c_str()) == 0;
}

// A Python interpreter that imports open3d: $FPP_PYTHON, Debian's own
// (where python3-open3d installs), then python3 on the PATH. Empty if none.
std::string python_with_open3d() {
    std::vector<std::string> candidates;
    if (const char* env = std::getenv("FPP_PYTHON"); env && *env)
        candidates.emplace_back(env);
    candidates.emplace_back("/usr/bin/python3");
    candidates.emplace_back("python3");
    for (const std::string& python : candidates) {
        const std::string probe = quoted(python) + " -c 'import open3d' > /dev/null 2>&1";
        if (std::system(probe.c_str()) == 0)
            return python;
    }
    return {};
}

// A small organised cloud: 7 x 5 slots, some without a point, coordinates
// that are not round in binary, quality, intensity and sigma_z per slot (so
// the readers also meet the optional sigma_z property; the simulated cloud
// below has the plain layout).
fpp::PointCloud small_cloud() {
    fpp::PointCloud c;
    c.xyz = fpp::Image<float>(7, 5, 3, kNaN);
    c.quality = fpp::Image<float>(7, 5, 1, kNaN);
    c.intensity = fpp::Image<float>(7, 5, 1, kNaN);
    c.sigma_z = fpp::Image<float>(7, 5, 1, kNaN);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x) {
            if ((x + 2 * y) % 4 == 1 || (x == 6 && y == 4))
                continue; // no point here
            const float fx = static_cast<float>(x), fy = static_cast<float>(y);
            c.xyz.at(x, y, 0) = -123.456f + 17.1f * fx + 0.001f * fy;
            c.xyz.at(x, y, 1) = 0.1f * fy - 1e-3f * fx;
            c.xyz.at(x, y, 2) = 480.0f + 1.0f / 3.0f * fx + 2000.125f * (y == 3 ? 1.0f : 0.0f);
            c.quality.at(x, y) = 10.5f + fx;
            c.intensity.at(x, y) = 100.25f - fy;
            c.sigma_z.at(x, y) = 0.0123f + 0.001f * fx * fy;
        }
    return c;
}

// A simulated scene's surface as the scanner would see it: the renderer's
// ground-truth points of the composite scene (relief and sphere over a
// plane) where the projector lights them, 4 x 4 binned camera (400 x 300).
fpp::PointCloud simulated_cloud() {
    const fpp::sim::Rig rig = fpp::sim::Rig::paper().without_effects().binned_camera(4);
    const fpp::sim::Renderer renderer(rig, fpp::sim::named_scene("composite"));
    fpp::PointCloud c;
    c.xyz = renderer.truth_xyz();
    c.quality = renderer.albedo();
    // Points only where the projector's light reaches (no point in its
    // shadows), as in a scan.
    const fpp::Image<float>& lit = renderer.truth_projector();
    for (std::size_t i = 0; i < c.xyz.pixel_count(); ++i)
        if (!std::isfinite(lit.data()[2 * i]))
            for (int k = 0; k < 3; ++k)
                c.xyz.data()[3 * i + std::size_t(k)] = kNaN;
    return c;
}

// The points a reader should see: finite slots in row-major order.
struct Expected {
    std::vector<float> x, y, z, quality;
};
Expected expected_points(const fpp::PointCloud& c) {
    Expected e;
    for (std::size_t i = 0; i < c.xyz.pixel_count(); ++i) {
        const float* p = c.xyz.data() + 3 * i;
        if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
            continue;
        e.x.push_back(p[0]);
        e.y.push_back(p[1]);
        e.z.push_back(p[2]);
        e.quality.push_back(c.quality.empty() ? kNaN : c.quality.data()[i]);
    }
    return e;
}

// Bitwise equality of coordinates (float -> the tool -> float is exact).
void expect_same_points(const Expected& want, const std::vector<float>& x,
                        const std::vector<float>& y, const std::vector<float>& z,
                        const std::string& tool) {
    ASSERT_EQ(x.size(), want.x.size()) << tool;
    ASSERT_EQ(y.size(), want.x.size()) << tool;
    ASSERT_EQ(z.size(), want.x.size()) << tool;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < want.x.size(); ++i) {
        const bool same = x[i] == want.x[i] && y[i] == want.y[i] && z[i] == want.z[i];
        if (!same && differ++ < 5)
            ADD_FAILURE() << tool << ": point " << i << " is (" << x[i] << ", " << y[i] << ", "
                          << z[i] << "), written (" << want.x[i] << ", " << want.y[i] << ", "
                          << want.z[i] << ")";
    }
    EXPECT_EQ(differ, 0u) << tool;
}

struct Case {
    const char* name;
    fpp::PointCloud cloud;
};
std::vector<Case> cases() {
    std::vector<Case> c;
    c.push_back({"small organised cloud", small_cloud()});
    c.push_back({"simulated composite scene", simulated_cloud()});
    return c;
}

TEST(PlyInterop, Open3dReadsOurPly) {
    const std::string python = python_with_open3d();
    FPP_REQUIRE_TOOL(!python.empty(), "python3 with open3d (Debian package python3-open3d)");
    const TempDir dir;
    // Open3D keeps NaN points unless asked; ours has none to keep.
    const fs::path script = dir / "read.py";
    std::ofstream(script) << "import sys\n"
                             "import numpy as np\n"
                             "import open3d as o3d\n"
                             "cloud = o3d.io.read_point_cloud(sys.argv[1], format='ply')\n"
                             "points = np.asarray(cloud.points)\n"
                             "points.astype('<f4').tofile(sys.argv[2])\n"
                             "low = points.min(axis=0)\n"
                             "high = points.max(axis=0)\n"
                             "print(len(points), *('%.9g' % v for v in (*low, *high)))\n";
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        const fs::path ply = dir / "cloud.ply", dump = dir / "points.f32", log = dir / "log.txt";
        fpp::write_ply(ply, c.cloud, {"interoperability test"});
        ASSERT_TRUE(run(quoted(python) + " " + quoted(script.string()) + " " +
                            quoted(ply.string()) + " " + quoted(dump.string()),
                        log))
            << read_text(log);
        const Expected want = expected_points(c.cloud);
        // Count and bounding box as Open3D prints them.
        std::istringstream printed(read_text(log));
        std::size_t count = 0;
        double box[6] = {};
        printed >> count >> box[0] >> box[1] >> box[2] >> box[3] >> box[4] >> box[5];
        ASSERT_TRUE(printed) << read_text(log);
        EXPECT_EQ(count, want.x.size());
        for (int axis = 0; axis < 3; ++axis) {
            const std::vector<float>& v = axis == 0 ? want.x : axis == 1 ? want.y : want.z;
            EXPECT_EQ(static_cast<float>(box[axis]), *std::min_element(v.begin(), v.end()));
            EXPECT_EQ(static_cast<float>(box[3 + axis]), *std::max_element(v.begin(), v.end()));
        }
        std::printf("%s: Open3D read %zu points, box (%.3f, %.3f, %.3f) .. (%.3f, %.3f, %.3f) mm\n",
                    c.name, count, box[0], box[1], box[2], box[3], box[4], box[5]);
        // Every coordinate, in order.
        const std::string raw = read_text(dump);
        ASSERT_EQ(raw.size(), 12 * want.x.size());
        std::vector<float> x(want.x.size()), y(x.size()), z(x.size());
        for (std::size_t i = 0; i < x.size(); ++i) {
            std::memcpy(&x[i], raw.data() + 12 * i, 4);
            std::memcpy(&y[i], raw.data() + 12 * i + 4, 4);
            std::memcpy(&z[i], raw.data() + 12 * i + 8, 4);
        }
        expect_same_points(want, x, y, z, "Open3D");
    }
}

TEST(PlyInterop, CloudCompareReadsOurPly) {
    FPP_REQUIRE_TOOL(on_path("CloudCompare"), "CloudCompare (Debian package cloudcompare)");
    const TempDir dir;
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        const fs::path ply = dir / "cloud.ply", out = dir / "cc.ply", log = dir / "log.txt";
        fs::remove(out);
        fpp::write_ply(ply, c.cloud);
        // Headless: no window (offscreen Qt platform), no dialogs (-SILENT);
        // its settings go to the temporary HOME.
        ASSERT_TRUE(run("HOME=" + quoted(dir.path().string()) +
                            " QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -AUTO_SAVE OFF -O " +
                            quoted(ply.string()) +
                            " -C_EXPORT_FMT PLY -PLY_EXPORT_FMT BINARY_LE -SAVE_CLOUDS FILE " +
                            quoted(out.string()),
                        log))
            << read_text(log);
        ASSERT_TRUE(fs::exists(out)) << read_text(log);
        const fpp::PlyPoints back = fpp::read_ply(out);
        std::printf("%s: CloudCompare read %zu points\n", c.name, back.size());
        expect_same_points(expected_points(c.cloud), back.x, back.y, back.z, "CloudCompare");
    }
}

TEST(PlyInterop, MeshLabReadsOurPly) {
    FPP_REQUIRE_TOOL(on_path("meshlabserver"), "meshlabserver (Debian package meshlab)");
    FPP_REQUIRE_TOOL(on_path("xvfb-run") && on_path("xauth"),
                     "xvfb-run and xauth (Debian packages xvfb, xauth)");
    const TempDir dir;
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        const fs::path ply = dir / "cloud.ply", out = dir / "meshlab.ply", log = dir / "log.txt";
        fs::remove(out);
        fpp::write_ply(ply, c.cloud);
        // -m vq: keep the vertex quality (our fringe modulation).
        ASSERT_TRUE(run("HOME=" + quoted(dir.path().string()) + " xvfb-run -a meshlabserver -i " +
                            quoted(ply.string()) + " -o " + quoted(out.string()) + " -m vq",
                        log))
            << read_text(log);
        ASSERT_TRUE(fs::exists(out)) << read_text(log);
        const fpp::PlyPoints back = fpp::read_ply(out);
        std::printf("%s: MeshLab read %zu points\n", c.name, back.size());
        const Expected want = expected_points(c.cloud);
        expect_same_points(want, back.x, back.y, back.z, "MeshLab");
        ASSERT_EQ(back.quality.size(), want.quality.size());
        std::size_t differ = 0;
        for (std::size_t i = 0; i < want.quality.size(); ++i)
            differ += back.quality[i] == want.quality[i] ? 0 : 1;
        EXPECT_EQ(differ, 0u) << "MeshLab: quality differs at " << differ << " points";
    }
}

} // namespace
