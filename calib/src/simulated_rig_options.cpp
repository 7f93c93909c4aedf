#include "simulated_rig_options.hpp"

namespace fpp::calib {

sim::Rig rig_from_options(const std::string& path, bool no_effects, double read_noise,
                          int binning) {
    sim::Rig rig = sim::load_rig(path);
    if (no_effects)
        rig = rig.without_effects();
    if (read_noise >= 0)
        rig.sensor.read_noise_dn = read_noise;
    if (binning > 1)
        rig = rig.binned_camera(binning);
    return rig;
}

} // namespace fpp::calib
