// A coefficient table (.fpt), memory-mapped and read into memory, with and
// without the expected camera size; every coefficient of an accepted table
// is read once (a mapping shorter than its header claims would fault here).
#include "fpp/coefficient_table.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::filesystem::path path =
        fpp::fuzz::write_input(fpp::fuzz::scratch() / "table.fpt", data, size);
    const fpp::Size camera{8, 6};
    for (const bool map : {true, false}) {
        for (const fpp::Size* expected : {static_cast<const fpp::Size*>(nullptr), &camera}) {
            fpp::fuzz::expect_declared_errors([&] {
                const fpp::CoefficientTable table = fpp::load_table(path, expected, map);
                const fpp::Size s = table.info().camera;
                volatile float sink = 0.0f; // keeps the reads
                for (int p = 0; p < table.planes(); ++p)
                    for (int y = 0; y < s.height; ++y)
                        for (int x = 0; x < s.width; ++x)
                            sink = table.get(p, x, y);
                (void)sink;
            });
        }
    }
    return 0;
}
