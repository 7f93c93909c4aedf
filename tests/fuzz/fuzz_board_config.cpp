// The scanner's board file (board/*.yaml): devices, store, http, sequence.
#include "fpp/scanner/board_config.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fpp::fuzz::expect_declared_errors([&] {
        const fpp::scanner::BoardConfig board =
            fpp::scanner::parse_board_config(fpp::fuzz::as_text(data, size), "board.yaml");
        (void)board.sequence(fpp::Size{1280, 800});
    });
    return 0;
}
