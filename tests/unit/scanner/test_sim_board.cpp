// The virtual scanner wired up as a board (fpp/scanner/sim_board.hpp), from
// board files written here: the rig binned as the file says, the clock it
// names, the trigger line wired to the camera, the devices handed to the
// scan, the records limited; a session scene's board written to the store;
// and the refusals (no sim section, a session scene or a scene that cannot
// be, a GigE link that is not there). (Scans on it: the integration tests.)

#include "fpp/scanner/sim_board.hpp"

#include "fpp/error.hpp"
#include "fpp/sim/sim_clock.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace fpp;
using namespace fpp::scanner;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

struct Fixture {
    test::TempDir dir;
    test::SimBoardYaml yaml;
    Fixture() { yaml.store = dir / "scans"; }
    BoardConfig board() const { return parse_board_config(yaml.text(), dir / "board.yaml"); }
};

std::string text_of(const fs::path& file) {
    std::ifstream in(file);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// The field and message of the InputError SimBoard throws for `yaml`.
std::pair<std::string, std::string> refusal(const Fixture& f) {
    try {
        SimBoard sim(f.board());
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), f.dir / "board.yaml");
        return {e.field(), e.what()};
    }
    return {"accepted", ""};
}

TEST(SimBoard, TheRigBinnedAndTheDevicesWiredAsTheBoardFileSays) {
    Fixture f;
    SimBoard sim(f.board());
    const sim::Rig full = sim::load_rig(sim::effects_rig_path());
    EXPECT_EQ(sim.rig().camera_size.width, full.camera_size.width / 4); // binning: 4
    EXPECT_EQ(sim.rig().camera_size.height, full.camera_size.height / 4);
    EXPECT_EQ(sim.camera().size(), sim.rig().camera_size);
    EXPECT_EQ(sim.display().size(), full.projector_size);
    EXPECT_NE(dynamic_cast<sim::VirtualClock*>(&sim.clock()), nullptr); // clock: virtual
    EXPECT_EQ(sim.session_board_yaml(), "");
    // The scan gets these very devices.
    const Devices d = sim.devices();
    EXPECT_EQ(&d.display, &sim.display());
    EXPECT_EQ(&d.camera, &sim.camera());
    EXPECT_EQ(&d.trigger, &sim.trigger());
    EXPECT_EQ(&d.button, &sim.button());
    EXPECT_EQ(&d.led, &sim.led());
    EXPECT_EQ(&d.clock, &sim.clock());
    // The trigger line reaches the camera, which exposes the pattern on screen.
    sim.display().prepare({Image<std::uint8_t>(sim.display().size(), 1, 255)});
    sim.display().show(0);
    sim.display().wait_flip(100ms);
    sim.camera().start();
    sim.trigger().pulse(100us);
    ASSERT_EQ(sim.camera().exposures().size(), 1u);
    EXPECT_EQ(sim.camera().exposures()[0].pattern, 0);
    EXPECT_EQ(sim.trigger().pulses().size(), 1u);
    EXPECT_EQ(sim.camera().exposures()[0].start_ns, sim.trigger().pulses()[0]);
    sim.camera().stop();
}

TEST(SimBoard, ASteadyClockWhenTheBoardFileAsksForIt) {
    Fixture f;
    f.yaml.steady_clock = true;
    SimBoard sim(f.board());
    EXPECT_EQ(dynamic_cast<sim::VirtualClock*>(&sim.clock()), nullptr);
}

TEST(SimBoard, RecordsAreLimitedForADaemonThatRunsForMonths) {
    Fixture f;
    SimBoard sim(f.board());
    sim.limit_records(4);
    for (int i = 0; i < 5; ++i) {
        sim.trigger().pulse(10us);
        sim.led().set(i % 2 ? drivers::LedState::ready : drivers::LedState::scanning);
    }
    EXPECT_EQ(sim.trigger().pulses().size(), 3u); // 4 reached: halved, then the fifth
    EXPECT_EQ(sim.led().history().size(), 4u);    // off and five: halved at the fifth record
    EXPECT_EQ(sim.led().state(), drivers::LedState::scanning);
}

TEST(SimBoard, ASessionScenesBoardIsWrittenToTheStoreOnce) {
    Fixture f;
    f.yaml.scene = "session:checkerboard:3";
    const fs::path board_yaml = f.dir / "scans" / "board.yaml";
    {
        SimBoard sim(f.board());
        ASSERT_TRUE(fs::exists(board_yaml));
        EXPECT_EQ(text_of(board_yaml), sim.session_board_yaml());
        EXPECT_NE(sim.session_board_yaml().find("fpp-board/1"), std::string::npos);
        EXPECT_NE(sim.session_board_yaml().find("checkerboard"), std::string::npos);
    }
    // One already there (a person's, or an earlier run's) is kept.
    std::ofstream(board_yaml) << "# mine\n";
    f.yaml.scene = "session:plane:2";
    SimBoard plane(f.board());
    EXPECT_EQ(text_of(board_yaml), "# mine\n");
    EXPECT_NE(plane.session_board_yaml().find("plane"), std::string::npos);
}

TEST(SimBoard, RefusesScenesThatCannotBeNamingTheField) {
    Fixture f;
    const std::string file = (f.dir / "board.yaml").string();
    f.yaml.scene = "session:triangle:3";
    EXPECT_EQ(refusal(f), std::make_pair(std::string("sim.scene"),
                                         file + ": sim.scene: session scene 'session:triangle:3': "
                                                "the board must be checkerboard or plane"));
    for (const char* poses : {"0", "201", "x"}) {
        f.yaml.scene = std::string("session:plane:") + poses;
        EXPECT_EQ(refusal(f).second, file + ": sim.scene: session scene 'session:plane:" + poses +
                                         "': give 1..200 poses, e.g. session:plane:15")
            << poses;
    }
    EXPECT_FALSE(fs::exists(f.dir / "scans" / "board.yaml")); // nothing written
}

TEST(SimBoard, RefusesABoardWithoutSimSectionAndAGigeLinkThatIsNotThere) {
    Fixture f;
    f.yaml.gige = true; // a hardware board: an Aravis camera, no sim section
    std::string text = f.yaml.text();
    text = text.substr(0, text.find("sim: {"));
    f.yaml.gige = false;
    const BoardConfig hardware = parse_board_config(text, f.dir / "hardware.yaml");
    try {
        SimBoard sim(hardware);
        FAIL() << "a sim board made of a hardware board";
    } catch (const std::logic_error& e) {
        EXPECT_STREQ(e.what(), "SimBoard on a board without a sim section");
    }
    SimBoard sim(f.board()); // camera.driver sim: no link
    try {
        sim.unplug_camera();
        FAIL() << "unplugged a link that is not there";
    } catch (const std::logic_error& e) {
        EXPECT_STREQ(e.what(), "SimBoard::unplug_camera: the board has no GigE link");
    }
    EXPECT_THROW(sim.plug_camera(), std::logic_error);
}

} // namespace
