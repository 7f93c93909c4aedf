#pragma once
// The text of a simulated board file (fpp-scanner-board/1, format in
// firmware/core/formats/board-file.md) for tests and benchmarks: GPIO lines 17, 27,
// 22 (unused by the sim), gray-x, 8 ms exposure, composite scene. Fields are
// laid out one way only, so that tests can replace a piece of text (e.g.
// "clock: virtual", "trigger: line", "seed: 3}") to make a variant.
// Header-only: it needs fpp_sim, which the support library does not link.
#include "fpp/simulator/rig.hpp"

#include <filesystem>
#include <string>

namespace fpp::test {

struct SimBoardYaml {
    std::string name = "test-sim";
    std::filesystem::path store;
    std::filesystem::path rig = sim::effects_rig_path();
    std::string table; // "table: ..." is written only when not empty
    int max_mb = 64;
    int binning = 4;
    int seed = 3;
    int flip_latency_us = 16667;
    bool steady_clock = false;
    // The camera through Aravis's fake GigE camera at 127.0.0.1 (software
    // trigger); otherwise the sim camera on the sim trigger line.
    bool gige = false;
    int frame_timeout_ms = 200;
    std::string sequence = "gray-x";
    std::string scene = "composite";
    std::string camera_extra; // more camera fields, e.g. ", noise: {...}"
    std::string extra;        // more top-level lines (hdr, points, projector_response)

    std::string text() const {
        const std::string camera =
            gige ? "camera: {driver: aravis, device: 127.0.0.1, pixel_format: Mono8, "
                   "exposure_us: 8000,\n"
                   "         trigger: software, trigger_source: Line0, packet_size: 0, "
                   "buffer_count: 4,\n"
                 : "camera: {driver: sim, device: \"\", pixel_format: Mono8, exposure_us: 8000,\n"
                   "         trigger: line, trigger_source: Line0, packet_size: 0, "
                   "buffer_count: 4,\n";
        return "format: fpp-scanner-board/1\n"
               "name: " +
               name +
               "\n"
               "display: {card: auto, connector: auto, mode: auto}\n"
               "gpio: {chip: gpiochip0, trigger_line: 17, button_line: 27, led_line: 22,\n"
               "       trigger_active_low: false, button_active_low: true, "
               "led_active_low: false,\n"
               "       debounce_ms: 30}\n" +
               camera + "         frame_timeout_ms: " + std::to_string(frame_timeout_ms) +
               camera_extra + "}\n" + "sequence: " + sequence + "\n" + extra +
               (table.empty() ? std::string() : "table: " + table + "\n") +
               "store: {directory: " + store.string() + ", max_mb: " + std::to_string(max_mb) +
               "}\n"
               "timing: {settle_us: 2000, trigger_pulse_us: 100, flip_timeout_ms: 100}\n"
               "sim: {rig: " +
               rig.string() + ", scene: " + scene + ", binning: " + std::to_string(binning) +
               ",\n"
               "      flip_latency_us: " +
               std::to_string(flip_latency_us) +
               ", clock: " + (steady_clock ? "steady" : "virtual") +
               ", seed: " + std::to_string(seed) + "}\n";
    }
};

} // namespace fpp::test
