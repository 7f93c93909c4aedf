// A simulated scene's YAML (list of shapes and materials).
#include "fpp/simulator/scene.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::filesystem::path path =
        fpp::fuzz::write_input(fpp::fuzz::scratch() / "scene.yaml", data, size);
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::sim::load_scene(path); });
    return 0;
}
