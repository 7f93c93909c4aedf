// Artefact files (fpp-artefact/1, firmware/core/formats/artefact.md): the
// three kinds and the repository's examples read; every malformed file is
// refused naming the file and the key.

#include "test_support.hpp"

#include "fpp/calib/artefact.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace {

using fpp::calib::Artefact;
using fpp::calib::ArtefactKind;
namespace fs = std::filesystem;

const std::string kBallBar = "format: fpp-artefact/1\n"
                             "kind: ball-bar\n"
                             "sphere_diameters_mm: [30.000, 30.002]\n"
                             "centre_distance_mm: 150.004\n"
                             "uncertainty_mm: 0.001\n";

Artefact parse(const std::string& text) {
    return fpp::calib::parse_artefact(text, "bar.yaml");
}

// The refusal of `text`: its field (key) and message.
fpp::InputError refusal(const std::string& text) {
    try {
        parse(text);
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), fs::path("bar.yaml"));
        return e;
    }
    ADD_FAILURE() << "accepted:\n" << text;
    return fpp::InputError("", "", "");
}

// kBallBar with one line replaced (or removed when `with` is empty).
std::string ball_bar_with(const std::string& line_start, const std::string& with) {
    std::string out;
    std::size_t at = 0;
    bool replaced = false;
    while (at < kBallBar.size()) {
        const std::size_t end = kBallBar.find('\n', at);
        const std::string line = kBallBar.substr(at, end - at);
        if (line.rfind(line_start, 0) == 0) {
            replaced = true;
            if (!with.empty())
                out += with + "\n";
        } else {
            out += line + "\n";
        }
        at = end + 1;
    }
    EXPECT_TRUE(replaced) << line_start;
    return out;
}

TEST(ArtefactFile, ReadsEachKind) {
    const Artefact bar = parse(kBallBar);
    EXPECT_EQ(bar.kind, ArtefactKind::ball_bar);
    ASSERT_EQ(bar.sphere_count(), 2u);
    EXPECT_DOUBLE_EQ(bar.sphere_diameters_mm[1], 30.002);
    EXPECT_DOUBLE_EQ(bar.centre_distance_mm, 150.004);
    EXPECT_DOUBLE_EQ(bar.uncertainty_mm, 0.001);
    EXPECT_TRUE(bar.name.empty());

    const Artefact sphere = parse("format: fpp-artefact/1\nkind: sphere\nname: S-30 no. 7\n"
                                  "sphere_diameters_mm: [25.4]\nuncertainty_mm: 0\n");
    EXPECT_EQ(sphere.kind, ArtefactKind::sphere);
    EXPECT_EQ(sphere.name, "S-30 no. 7");
    EXPECT_EQ(sphere.sphere_diameters_mm, std::vector<double>{25.4});

    const Artefact plane = parse("format: fpp-artefact/1\nkind: plane\nplane_size_mm: [200, 150]\n"
                                 "flatness_mm: 0.002\nuncertainty_mm: 0.001\n");
    EXPECT_EQ(plane.kind, ArtefactKind::plane);
    EXPECT_DOUBLE_EQ(plane.plane_width_mm, 200);
    EXPECT_DOUBLE_EQ(plane.plane_height_mm, 150);
    EXPECT_DOUBLE_EQ(plane.flatness_mm, 0.002);
    EXPECT_EQ(plane.sphere_count(), 0u);
}

TEST(ArtefactFile, ReadsTheRepositoryExamples) {
    for (const char* name : {"ball-bar-150.yaml", "sphere-30.yaml", "flat-200x150.yaml"}) {
        const fs::path path = fpp::test::source_dir() / "board/sim/artefacts" / name;
        const Artefact a = fpp::calib::read_artefact(path);
        EXPECT_EQ(a.origin, path);
    }
}

TEST(ArtefactFile, RefusesAMissingFileNamingIt) {
    fpp::test::TempDir dir;
    try {
        fpp::calib::read_artefact(dir / "nowhere.yaml");
        FAIL() << "read a missing file";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), dir / "nowhere.yaml");
    }
}

struct Bad {
    const char* what;
    std::string text;
    const char* field;   // the key the refusal names
    const char* message; // a part of its message
};

TEST(ArtefactFile, RefusesEachMalformedKeyNamingIt) {
    const Bad cases[] = {
        {"not YAML", "format: [fpp-artefact/1\n", "", "not valid YAML"},
        {"not a map", "- 1\n- 2\n", "(top level)", "expected a map"},
        {"no format", ball_bar_with("format:", ""), "format", "missing field"},
        {"another format", ball_bar_with("format:", "format: fpp-artefact/2"), "format",
         "unknown format"},
        {"no kind", ball_bar_with("kind:", ""), "kind", "missing field"},
        {"unknown kind", ball_bar_with("kind:", "kind: gauge-block"), "kind", "unknown kind"},
        {"unknown key", kBallBar + "temperature_c: 20\n", "temperature_c", "unknown"},
        {"key of another kind", kBallBar + "flatness_mm: 0.001\n", "flatness_mm", "unknown"},
        {"duplicate key", kBallBar + "uncertainty_mm: 0.002\n", "uncertainty_mm", "twice"},
        {"no diameters", ball_bar_with("sphere_diameters_mm", ""), "sphere_diameters_mm",
         "missing field"},
        {"one diameter for a bar",
         ball_bar_with("sphere_diameters_mm", "sphere_diameters_mm: [30]"), "sphere_diameters_mm",
         "give 2 diameters"},
        {"diameters not a list", ball_bar_with("sphere_diameters_mm", "sphere_diameters_mm: 30"),
         "sphere_diameters_mm", "list"},
        {"zero diameter", ball_bar_with("sphere_diameters_mm", "sphere_diameters_mm: [30, 0]"),
         "sphere_diameters_mm[1]", "outside"},
        {"text diameter", ball_bar_with("sphere_diameters_mm", "sphere_diameters_mm: [30, big]"),
         "sphere_diameters_mm[1]", ""},
        {"quoted diameter", ball_bar_with("sphere_diameters_mm", "sphere_diameters_mm: ['30', 30]"),
         "sphere_diameters_mm[0]", ""},
        {"non-finite diameter",
         ball_bar_with("sphere_diameters_mm", "sphere_diameters_mm: [.nan, 30]"),
         "sphere_diameters_mm[0]", "non-finite"},
        {"no distance", ball_bar_with("centre_distance_mm", ""), "centre_distance_mm",
         "missing field"},
        {"spheres touch", ball_bar_with("centre_distance_mm", "centre_distance_mm: 30.0"),
         "centre_distance_mm", "touch or overlap"},
        {"negative distance", ball_bar_with("centre_distance_mm", "centre_distance_mm: -150"),
         "centre_distance_mm", "outside"},
        {"no uncertainty", ball_bar_with("uncertainty_mm", ""), "uncertainty_mm", "missing field"},
        {"negative uncertainty", ball_bar_with("uncertainty_mm", "uncertainty_mm: -0.001"),
         "uncertainty_mm", "outside"},
        {"uncertainty in micrometres", ball_bar_with("uncertainty_mm", "uncertainty_mm: 1.5"),
         "uncertainty_mm", "micrometres"},
        {"empty name", kBallBar + "name: ''\n", "name", "1 to 128"},
        {"distance on a sphere",
         "format: fpp-artefact/1\nkind: sphere\nsphere_diameters_mm: [30]\n"
         "centre_distance_mm: 150\nuncertainty_mm: 0.001\n",
         "centre_distance_mm", "unknown"},
        {"two diameters for a sphere",
         "format: fpp-artefact/1\nkind: sphere\nsphere_diameters_mm: [30, 30]\n"
         "uncertainty_mm: 0.001\n",
         "sphere_diameters_mm", "give 1 diameter"},
        {"plane without size",
         "format: fpp-artefact/1\nkind: plane\nflatness_mm: 0.002\nuncertainty_mm: 0.001\n",
         "plane_size_mm", "missing field"},
        {"plane size of 3",
         "format: fpp-artefact/1\nkind: plane\nplane_size_mm: [1, 2, 3]\nflatness_mm: 0.002\n"
         "uncertainty_mm: 0.001\n",
         "plane_size_mm", "list of 2"},
        {"plane of zero height",
         "format: fpp-artefact/1\nkind: plane\nplane_size_mm: [200, 0]\nflatness_mm: 0.002\n"
         "uncertainty_mm: 0.001\n",
         "plane_size_mm[1]", "outside"},
        {"plane without flatness",
         "format: fpp-artefact/1\nkind: plane\nplane_size_mm: [200, 150]\n"
         "uncertainty_mm: 0.001\n",
         "flatness_mm", "missing field"},
        {"flatness in micrometres",
         "format: fpp-artefact/1\nkind: plane\nplane_size_mm: [200, 150]\nflatness_mm: 2\n"
         "uncertainty_mm: 0.001\n",
         "flatness_mm", "micrometres"},
        {"diameters on a plane",
         "format: fpp-artefact/1\nkind: plane\nplane_size_mm: [200, 150]\nflatness_mm: 0.002\n"
         "sphere_diameters_mm: [30]\nuncertainty_mm: 0.001\n",
         "sphere_diameters_mm", "unknown"},
    };
    for (const Bad& bad : cases) {
        SCOPED_TRACE(bad.what);
        const fpp::InputError e = refusal(bad.text);
        EXPECT_EQ(e.field(), bad.field) << e.what();
        EXPECT_NE(std::string(e.what()).find(bad.message), std::string::npos) << e.what();
    }
}

} // namespace
