// A TIFF: grey camera frames (8/16 bit) and float images (truth, phase maps).
#include "fpp/image_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::filesystem::path path =
        fpp::fuzz::write_input(fpp::fuzz::scratch() / "frame.tiff", data, size);
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_tiff_gray_info(path); });
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_frame_info(path); });
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_tiff_gray(path); });
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_frame(path); });
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_tiff_float(path); });
    return 0;
}
