#pragma once
// The two-camera path of `fpp-calib reconstruct` (cmd_reconstruct_pair.cpp).

#include "fpp/decoder.hpp"

#include <string>

namespace fpp::calib {

struct ReconstructPairArgs {
    std::string first_capture;  // camera 1 (its frame is the cloud's)
    std::string second_capture; // camera 2, the same pattern sequence
    std::string calibration;    // camera-camera calibration (fpp/calib/camera_pair.hpp)
    std::string table;          // refused when given: a table is a camera-projector model
    std::string out;            // cloud.ply
    std::string xyz;            // optional XYZ TIFF
    std::string axes = "auto";  // auto | x | xy
    DecodeOptions decode;
};

// Decodes both captures, matches and triangulates (fpp/calib/two_camera.hpp),
// writes the PLY (and TIFF); returns the exit code. Throws InputError naming
// the file and field for every refusal, including nothing matched.
int run_reconstruct_pair(const ReconstructPairArgs& args);

} // namespace fpp::calib
