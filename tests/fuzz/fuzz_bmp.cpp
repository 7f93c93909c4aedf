// A BMP camera frame (our own reader).
#include "fpp/image_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::filesystem::path path =
        fpp::fuzz::write_input(fpp::fuzz::scratch() / "frame.bmp", data, size);
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_bmp_gray_info(path); });
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_frame_info(path); });
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_bmp_gray(path); });
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_frame(path); });
    return 0;
}
