// fpp_test_truth_table RIG.yaml BINNING OUT.fpt: writes the coefficient table
// of a simulated rig's true geometry (rig_truth_table.hpp) for the camera
// binned BINNING x BINNING, so that tests outside C++ (tests/api) get a valid
// table for a sim board without a calibration session.
#include "fpp/coefficient_table.hpp"
#include "fpp/simulator/rig.hpp"
#include "rig_truth_table.hpp"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: %s RIG.yaml BINNING OUT.fpt\n", argv[0]);
        return 2;
    }
    try {
        const int binning = std::stoi(argv[2]);
        if (binning < 1 || binning > 16) {
            std::fprintf(stderr, "BINNING: must be 1 to 16\n");
            return 2;
        }
        const fpp::sim::Rig rig = fpp::sim::load_rig(argv[1]).binned_camera(binning);
        fpp::write_table(argv[3], fpp::test::rig_truth_table(rig));
        std::printf("%s: %dx%d camera, %dx%d projector\n", argv[3], rig.camera_size.width,
                    rig.camera_size.height, rig.projector_size.width, rig.projector_size.height);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
