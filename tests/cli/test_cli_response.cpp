// fpp-calib simulate-session's response ramp, `response` and `calibrate`
// with a ramp, run as a person would: exit codes, files written, and on a
// bad ramp an error naming the file and the field, exit code 2 and nothing
// written. Sessions use the camera binned 4x (400 x 300).

#include "test_support.hpp"

#include "fpp/image_io.hpp"
#include "fpp/projector_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

namespace {

using fpp::test::TempDir;
using fpp::test::ToolRun;
namespace fs = std::filesystem;

std::string quote(const fs::path& p) {
    return fpp::test::shell_quote(p.string());
}

ToolRun run_calib(const std::string& args, const TempDir& scratch) {
    return fpp::test::run_tool(fpp::test::calib_exe(), args, scratch.path());
}

bool contains(const std::string& text, const std::string& what) {
    return text.find(what) != std::string::npos;
}

fs::path simulate_session(const TempDir& dir, const std::string& name, int poses) {
    const fs::path session = dir / name;
    const ToolRun run = run_calib("simulate-session --poses " + std::to_string(poses) +
                                      " --binning 4 --out " + quote(session),
                                  dir);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return session;
}

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

} // namespace

TEST(CliResponse, SimulatedSessionHoldsARampThatResponseFits) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 1);
    ASSERT_TRUE(fs::exists(session / "response" / "ramp.yaml"));
    const fpp::ResponseRamp ramp = fpp::read_response_ramp(session / "response");
    EXPECT_EQ(ramp.levels, fpp::standard_ramp_levels());
    EXPECT_EQ(ramp.frames.front().size(), (fpp::Size{400, 300}));
    EXPECT_TRUE(contains(ramp.metadata_yaml, "projector_gamma: 2.2")) << ramp.metadata_yaml;

    // From the session, and from the ramp folder itself.
    for (const fs::path& input : {session, session / "response"}) {
        const fs::path out = dir / ("response-" + input.filename().string() + ".yaml");
        const ToolRun run = run_calib("response " + quote(input) + " --out " + quote(out), dir);
        ASSERT_EQ(run.exit_code, 0) << run.output;
        EXPECT_TRUE(contains(run.output, "camera pixels used")) << run.output;
        EXPECT_TRUE(contains(run.output, "worst error against the simulated rig's response"))
            << run.output;
        const fpp::ProjectorResponse r = fpp::load_projector_response(out);
        ASSERT_EQ(r.levels.size(), 17u);
        double worst = 0;
        for (std::size_t k = 0; k < r.levels.size(); ++k)
            worst = std::max(worst, std::abs(r.emitted[k] - std::pow(r.levels[k] / 255.0, 2.2)));
        std::printf("fpp-calib response on a simulated session: %zu pixels, worst level error "
                    "%.5f\n",
                    r.pixels_used, worst);
        EXPECT_LT(worst, 0.002);
        EXPECT_GT(r.pixels_used, 50000u); // the board's white parts at the first pose
    }
}

TEST(CliResponse, ABadRampExitsWithCode2NamingTheFieldAndWritesNothing) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 1);
    const fs::path ramp = session / "response";
    const fs::path out = dir / "response.yaml";

    // Levels 128 and 144 swapped on disk: the light falls at 144.
    fs::rename(ramp / "level-128.png", ramp / "swap.png");
    fs::rename(ramp / "level-144.png", ramp / "level-128.png");
    fs::rename(ramp / "swap.png", ramp / "level-144.png");
    ToolRun run = run_calib("response " + quote(session) + " --out " + quote(out), dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, (ramp / "ramp.yaml").string() + ": levels[9]: "))
        << run.output;
    EXPECT_TRUE(contains(run.output, "not monotonic")) << run.output;
    EXPECT_FALSE(fs::exists(out));

    // A malformed ramp.yaml.
    write_text(ramp / "ramp.yaml", "format: fpp-response-ramp/1\nlevels: [0, 128, 254]\n"
                                   "frames: [level-000.png, level-128.png, level-255.png]\n");
    run = run_calib("response " + quote(ramp) + " --out " + quote(out), dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "levels[2]: the last level must be 255")) << run.output;
    EXPECT_FALSE(fs::exists(out));

    // No ramp at all.
    run = run_calib("response " + quote(dir / "nothing") + " --out " + quote(out), dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "holds neither ramp.yaml")) << run.output;
    EXPECT_FALSE(fs::exists(out));
}

TEST(CliResponse, CalibrateWritesTheResponseWhenTheSessionHasARamp) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 6);
    fs::create_directory(dir / "out");
    const fs::path calib = dir / "out" / "calib.yaml", table = dir / "out" / "table.fpt";
    const ToolRun run = run_calib(
        "calibrate " + quote(session) + " --out " + quote(calib) + " --table " + quote(table), dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(fs::exists(calib));
    EXPECT_TRUE(fs::exists(table));
    const fs::path response = dir / "out" / "projector-response.yaml";
    ASSERT_TRUE(fs::exists(response)) << run.output;
    EXPECT_NEAR(fpp::load_projector_response(response).at(128), std::pow(128 / 255.0, 2.2), 0.002);
    // The ramp's folder is not taken for a pose.
    EXPECT_TRUE(contains(run.output, "of 6 poses")) << run.output;

    // A bad ramp stops calibrate before the work, writing nothing.
    fs::remove(session / "response" / "level-255.png");
    fs::create_directory(dir / "out2");
    const ToolRun bad =
        run_calib("calibrate " + quote(session) + " --out " + quote(dir / "out2" / "calib.yaml") +
                      " --table " + quote(dir / "out2" / "table.fpt"),
                  dir);
    EXPECT_EQ(bad.exit_code, 2) << bad.output;
    EXPECT_TRUE(contains(bad.output, "frames[16]")) << bad.output;
    EXPECT_TRUE(fs::is_empty(dir / "out2"));
}
