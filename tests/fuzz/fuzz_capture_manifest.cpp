// capture.yaml alone (fpp-capture/1 and /2, every block form): the parser,
// then, for a manifest it accepted, the writer and the parser again, which
// must give back an equal manifest (what fpp-calib writes, it reads).
#include "fpp/capture_set.hpp"
#include "fuzz_support.hpp"

#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fpp::fuzz::expect_declared_errors([&] {
        const fpp::CaptureManifest manifest =
            fpp::parse_manifest(fpp::fuzz::as_text(data, size), "capture.yaml");
        // Accepted once: the writer must take it and the reader take that back.
        const std::string again = fpp::manifest_to_yaml(manifest);
        try {
            (void)fpp::parse_manifest(again, "rewritten.yaml");
        } catch (const fpp::InputError&) {
            std::abort(); // the writer wrote what the reader refuses
        }
    });
    return 0;
}
