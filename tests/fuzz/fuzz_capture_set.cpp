// A capture folder: capture.yaml from the fuzzer beside a fixed set of small
// frames (8- and 16-bit PNG 8 x 6, a grey BMP 5 x 3, a 16-bit TIFF 2 x 2),
// read whole: manifest, frame names, frame headers, depths and values, and
// truth files. The frame names the manifest holds reach the file system, so
// this finds what bad names do there.
#include "fpp/capture_set.hpp"
#include "fpp/image_io.hpp"
#include "fuzz_support.hpp"

#include <cstdint>
#include <filesystem>

namespace fs = std::filesystem;

namespace {

// The folder's frames, written once per process.
const fs::path& capture_folder() {
    static const fs::path folder = [] {
        const fs::path f = fpp::fuzz::scratch() / "capture";
        fs::create_directories(f);
        fpp::Image<std::uint8_t> grey8(fpp::Size{8, 6}, 1);
        fpp::Image<std::uint16_t> grey16(fpp::Size{8, 6}, 1);
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 8; ++x) {
                grey8.at(x, y) = static_cast<std::uint8_t>(30 * x + y);
                grey16.at(x, y) = static_cast<std::uint16_t>(4000 * x + 7 * y);
            }
        for (const char* name : {"f0.png", "f1.png", "f2.png", "f3.png", "f4.png", "f5.png"})
            fpp::write_png(f / name, grey8);
        fpp::write_png(f / "g0.png", grey16);
        fpp::write_png(f / "g1.png", grey16);
        const fs::path data = FPP_TEST_DATA_DIR;
        fs::copy_file(data / "frame_io/opencv_grey8_5x3.bmp", f / "b0.bmp");
        fs::copy_file(data / "image_io/uint16_2x2.tiff", f / "t0.tiff");
        fs::copy_file(data / "image_io/float32_be_2x2.tiff", f / "xyz.tiff");
        return f;
    }();
    return folder;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const fs::path& folder = capture_folder();
    fpp::fuzz::write_input(folder / "capture.yaml", data, size);
    fpp::fuzz::expect_declared_errors([&] { (void)fpp::read_capture_set(folder); });
    return 0;
}
