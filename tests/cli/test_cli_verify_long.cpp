// fpp-calib verify end to end at full size: the ball bar on its stand before
// a wall at all seven VDI/VDE 2634-2 positions (tests/support/ball_bar_scene.hpp)
// on the effects rig (gamma, defocus, noise; 1600 x 1200 camera), with the
// table of the rig's true geometry: every position's SD within 0.005 mm of
// the SD of the true sphere centres, and the verdict against the MPEs given.

#include "ball_bar_scene.hpp"
#include "rig_truth_table.hpp"
#include "test_support.hpp"

#include "fpp/coefficient_table.hpp"
#include "fpp/simulator/rig.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

std::string q(const fs::path& p) {
    return fpp::test::shell_quote(p.string());
}

TEST(CliVerifyLong, SevenPositionsAtFullSizeMeetTheTruth) {
    fpp::test::TempDir dir;
    const fpp::sim::Rig rig = fpp::sim::load_rig(fpp::sim::effects_rig_path());
    fpp::write_table(dir / "table.fpt", fpp::test::rig_truth_table(rig));
    std::ofstream(dir / "bar.yaml") << fpp::test::ball_bar_artefact_yaml();
    const auto& positions = fpp::test::vdi_ball_bar_positions();
    std::string captures;
    for (std::size_t k = 0; k < positions.size(); ++k) {
        const std::string name = "position-" + std::to_string(k + 1);
        std::ofstream(dir / (name + ".yaml")) << fpp::test::ball_bar_scene_yaml(positions[k]);
        const fpp::test::ToolRun sim =
            fpp::test::run_tool(fpp::test::calib_exe(),
                                "simulate --rig " + q(fpp::sim::effects_rig_path()) + " --scene " +
                                    q(dir / (name + ".yaml")) + " --sequence gray-x --seed " +
                                    std::to_string(k + 1) + " --out " + q(dir / name),
                                dir.path());
        ASSERT_EQ(sim.exit_code, 0) << sim.output;
        captures += " " + q(dir / name);
    }
    const fpp::test::ToolRun run = fpp::test::run_tool(
        fpp::test::calib_exe(),
        "verify --artefact " + q(dir / "bar.yaml") + " --table " + q(dir / "table.fpt") +
            " --mpe-sd 0.02 --mpe-pf 0.3 --mpe-ps 0.03 --report " + q(dir / "report") + captures,
        dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    std::ifstream in(dir / "report/verification.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    ASSERT_EQ(j["sphere_spacing_error_mm"].size(), positions.size());
    for (std::size_t k = 0; k < positions.size(); ++k) {
        const double sd = j["sphere_spacing_error_mm"][k].get<double>();
        const double truth = positions[k].length - fpp::test::kBallBarLengthMm;
        EXPECT_NEAR(sd, truth, 0.005) << "position " << k + 1;
        std::printf("position %zu: SD %+.4f mm (true %+.4f mm)", k + 1, sd, truth);
        for (const nlohmann::json& s : j["positions"][k]["spheres"])
            std::printf(", sphere %d P_F %.4f P_S %+.4f coverage %.2f (%d points)",
                        s["sphere"].get<int>(), s["probing_form_mm"].get<double>(),
                        s["probing_size_mm"].get<double>(), s["coverage"].get<double>(),
                        s["points_used"].get<int>());
        std::printf("\n");
    }
}

} // namespace
