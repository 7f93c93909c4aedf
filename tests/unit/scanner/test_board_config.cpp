// The board file (fpp/scanner/board_config.hpp, format
// firmware/core/formats/board-file.md): every field refused by name, the
// camera-only simulated board's conditions, and every shipped board valid.
#include <gtest/gtest.h>

#include "fpp/error.hpp"
#include "fpp/scanner/board_config.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"

#include <filesystem>
#include <string>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;

namespace {

// The test board: camera binned 4 x 4 (400 x 300), virtual clock.
std::string board_yaml(const fs::path& store, const std::string& table = "") {
    fpp::test::SimBoardYaml b;
    b.store = store;
    b.table = table;
    return b.text();
}

} // namespace

TEST(BoardConfig, CameraOnlyNeedsSoftwareTriggerAndSteadyClock) {
    fpp::test::TempDir dir;
    std::string text = board_yaml(dir / "scans");
    auto with = [&](const std::string& from, const std::string& to) {
        std::string t = text;
        t.replace(t.find(from), from.size(), to);
        return t;
    };
    const std::string camera_only = with("seed: 3", "seed: 3, camera_only: true");
    const std::string ok = [&] {
        std::string t = camera_only;
        t.replace(t.find("trigger: line"), 13, "trigger: software");
        t.replace(t.find("clock: virtual"), 14, "clock: steady");
        return t;
    }();
    const BoardConfig b = parse_board_config(ok, dir / "board.yaml");
    ASSERT_TRUE(b.sim.has_value());
    EXPECT_TRUE(b.sim->camera_only);
    auto field_of = [&](const std::string& yaml) {
        try {
            parse_board_config(yaml, dir / "board.yaml");
        } catch (const InputError& e) {
            return e.field();
        }
        return std::string("accepted");
    };
    std::string line_trigger = ok;
    line_trigger.replace(line_trigger.find("trigger: software"), 17, "trigger: line");
    EXPECT_EQ(field_of(line_trigger), "camera.trigger");
    std::string virtual_clock = ok;
    virtual_clock.replace(virtual_clock.find("clock: steady"), 13, "clock: virtual");
    EXPECT_EQ(field_of(virtual_clock), "sim.clock");
    std::string not_bool = ok;
    not_bool.replace(not_bool.find("camera_only: true"), 17, "camera_only: yes please");
    EXPECT_EQ(field_of(not_bool), "sim.camera_only");
}

TEST(BoardConfig, RejectsBadFieldsNamingThem) {
    fpp::test::TempDir dir;
    const std::string good = board_yaml(dir / "scans", "t.fpt");
    EXPECT_NO_THROW(parse_board_config(good, dir / "b.yaml"));
    auto expect_field = [&](const std::string& from, const std::string& to,
                            const std::string& field) {
        std::string text = good;
        const auto at = text.find(from);
        ASSERT_NE(at, std::string::npos) << from;
        text.replace(at, from.size(), to);
        try {
            parse_board_config(text, dir / "b.yaml");
            ADD_FAILURE() << "accepted " << to;
        } catch (const InputError& e) {
            EXPECT_EQ(e.field(), field) << e.what();
            EXPECT_EQ(e.file(), dir / "b.yaml");
        }
    };
    expect_field("trigger_line: 17", "trigger_line: -1", "gpio.trigger_line");
    expect_field("button_line: 27", "button_line: 17", "gpio");
    expect_field("driver: sim", "driver: v4l2", "camera.driver");
    expect_field("pixel_format: Mono8", "pixel_format: RGB8", "camera.pixel_format");
    expect_field("sequence: gray-x", "sequence: nope", "sequence");
    expect_field("mode: auto", "mode: big", "display.mode");
    expect_field("settle_us: 2000", "settle_us: \"2000\"", "timing.settle_us");
    expect_field("clock: virtual", "clock: wall", "sim.clock");
    expect_field("max_mb: 64", "max_mb: 64, extra: 1", "store.extra");
}

TEST(BoardConfig, ShippedBoardFilesAreValid) {
    // Every board description under board/ reads; the hardware ones drive an
    // Aravis camera from a line trigger, the simulated ones carry a sim
    // section.
    int hardware = 0, simulated = 0;
    for (const auto& e : fs::directory_iterator(fpp::test::source_dir() / "board")) {
        if (e.path().extension() != ".yaml")
            continue;
        SCOPED_TRACE(e.path().string());
        const BoardConfig b = read_board_config(e.path());
        if (b.sim) {
            ++simulated;
            continue;
        }
        ++hardware;
        EXPECT_EQ(b.camera.driver, CameraDriver::aravis);
        EXPECT_EQ(b.camera.settings.trigger, drivers::TriggerMode::line);
        EXPECT_TRUE(b.table.has_value());
        EXPECT_NE(b.gpio.trigger_line, b.gpio.button_line);
        EXPECT_NE(b.gpio.led_line, b.gpio.button_line);
        EXPECT_NE(b.gpio.led_line, b.gpio.trigger_line);
    }
    EXPECT_GE(hardware, 2); // Raspberry Pi 5, ROCK 5B
    EXPECT_GE(simulated, 4);
}
