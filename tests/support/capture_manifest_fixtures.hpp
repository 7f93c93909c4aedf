#pragma once
// A valid capture manifest and the checks of a named rejection, shared by the
// capture-set tests (tests/unit/core/test_capture_set*.cpp,
// test_capture_manifest_rejects.cpp).

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace fpp::test {

// A valid manifest: 16x12 camera, 64x40 projector; 1 + 3 + 4 = 8 frames.
inline const std::string kValid = R"(format: fpp-capture/1
camera:    {width: 16, height: 12}
projector: {width: 64, height: 40}
frames: [f0.png, f1.png, f2.png, f3.png, f4.png, f5.png, f6.png, f7.png]
sequence:
  - pattern: white
  - pattern: phase
    axis: x
    period: 8.0
    steps: 3
  - pattern: gray
    axis: x
    period: 8.0
    bits: 3
    complementary: true
metadata:
  exposure_us: 8000
)";

inline const std::filesystem::path kOrigin = "/captures/pose-07/capture.yaml";

// kValid with `from` (which must occur) replaced by `to`.
inline std::string with(const std::string& from, const std::string& to, std::string text = kValid) {
    const auto at = text.find(from);
    if (at == std::string::npos)
        throw std::logic_error("test text lacks: " + from);
    return text.replace(at, from.size(), to);
}

// Runs f; expects an InputError naming `file` and exactly `field`, whose
// message mentions both and contains `hint` if given.
template <class F>
void expect_input_error(F&& f, const std::filesystem::path& file, const std::string& field,
                        const std::string& hint = "") {
    try {
        f();
        ADD_FAILURE() << "accepted; expected a rejection of " << field;
    } catch (const fpp::InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.file(), file) << what;
        EXPECT_EQ(e.field(), field) << what;
        EXPECT_NE(what.find(file.string()), std::string::npos) << what;
        EXPECT_NE(what.find(field), std::string::npos) << what;
        if (!hint.empty()) {
            EXPECT_NE(what.find(hint), std::string::npos) << what;
        }
    }
}

inline void expect_rejected(const std::string& yaml, const std::string& field,
                            const std::string& hint = "") {
    expect_input_error([&] { fpp::parse_manifest(yaml, kOrigin); }, kOrigin, field, hint);
}

} // namespace fpp::test
