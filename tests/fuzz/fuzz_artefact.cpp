// A certified artefact's file for fpp-calib verify (fpp-artefact/1).
#include "fpp/calib/artefact.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text = fpp::fuzz::as_text(data, size);
    fpp::fuzz::expect_declared_errors(
        [&] { (void)fpp::calib::parse_artefact(text, "artefact.yaml"); });
    return 0;
}
