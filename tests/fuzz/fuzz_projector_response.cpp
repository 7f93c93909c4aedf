// fpp-projector-response/1 YAML (what `fpp-calib response` writes and the
// scanner's board file names).
#include "fpp/projector_response.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fpp::fuzz::expect_declared_errors([&] {
        (void)fpp::parse_projector_response(fpp::fuzz::as_text(data, size), "response.yaml");
    });
    return 0;
}
