// A scan sequence file (a `sequence:` list, as board configs and named scan
// sequences hold it), then the checks for a 1280 x 800 projector.
#include "fpp/capture_set.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fpp::fuzz::expect_declared_errors([&] {
        const fpp::Sequence sequence =
            fpp::parse_sequence(fpp::fuzz::as_text(data, size), "sequence.yaml");
        fpp::validate_sequence(sequence, fpp::Size{1280, 800}, "sequence.yaml");
    });
    return 0;
}
