// board.yaml of a calibration session (checkerboard or plane).
#include "fpp/capture_set.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fpp::fuzz::expect_declared_errors(
        [&] { (void)fpp::parse_board(fpp::fuzz::as_text(data, size), "board.yaml"); });
    return 0;
}
