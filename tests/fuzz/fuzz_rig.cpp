// A simulated rig's YAML (board/sim/*.yaml): lenses, poses, sensor, noise.
#include "fpp/simulator/rig.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::filesystem::path path =
        fpp::fuzz::write_input(fpp::fuzz::scratch() / "rig.yaml", data, size);
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::sim::load_rig(path); });
    return 0;
}
