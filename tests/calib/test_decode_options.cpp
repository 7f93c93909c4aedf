// The decoder's options as a user gives them (fpp/calib/decode_options.hpp):
// a value DecodeOptions::validate() refuses is refused again naming the
// option as that user spelt it: fpp-calib's flag on the command line, the
// keyword of the Python package's function.

#include "fpp/calib/decode_options.hpp"

#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <string>

using fpp::DecodeOptions;
using fpp::InputError;
using fpp::calib::check_decode_options;
using fpp::calib::OptionSpelling;

namespace {

struct Refusal {
    std::string file, field, what;
};

Refusal refusal(const DecodeOptions& options,
                OptionSpelling spelling = OptionSpelling::command_line,
                const std::string& origin = "command line") {
    try {
        check_decode_options(options, spelling, origin);
    } catch (const InputError& e) {
        return {e.file().string(), e.field(), e.what()};
    }
    return {"accepted", "", ""};
}

DecodeOptions with_min_modulation(double v) {
    DecodeOptions o;
    o.min_modulation = v;
    return o;
}
DecodeOptions with_threads(int v) {
    DecodeOptions o;
    o.threads = v;
    return o;
}

TEST(DecodeOptions, ValidOptionsPass) {
    EXPECT_NO_THROW(check_decode_options(DecodeOptions{}));
    EXPECT_NO_THROW(check_decode_options(with_min_modulation(0.0)));
    EXPECT_NO_THROW(
        check_decode_options(with_threads(1024), OptionSpelling::keyword, "fpp.decode"));
}

TEST(DecodeOptions, OnTheCommandLineTheFlagIsNamed) {
    const Refusal m = refusal(with_min_modulation(1.5));
    EXPECT_EQ(m.file, "command line");
    EXPECT_EQ(m.field, "--min-modulation");
    EXPECT_EQ(m.what, "command line: --min-modulation: must be in [0, 1), got 1.500000");
    const Refusal t = refusal(with_threads(-1));
    EXPECT_EQ(t.field, "--threads");
    EXPECT_EQ(t.what, "command line: --threads: must be in [0, 1024], got -1.000000");
    EXPECT_EQ(refusal(with_threads(1025)).what,
              "command line: --threads: must be in [0, 1024], got 1025.000000");
}

TEST(DecodeOptions, OptionsWithoutAFlagAreNamedAsDecodeOptions) {
    DecodeOptions o;
    o.saturation = 0;
    const Refusal r = refusal(o);
    EXPECT_EQ(r.field, "decode options: saturation");
    EXPECT_EQ(r.what, "command line: decode options: saturation: must be in (0, 1], got 0.000000");
}

TEST(DecodeOptions, AKeywordIsNamedWithTheFunction) {
    const Refusal m = refusal(with_min_modulation(-0.25), OptionSpelling::keyword, "fpp.decode");
    EXPECT_EQ(m.file, "fpp.decode");
    EXPECT_EQ(m.field, "min_modulation");
    EXPECT_EQ(m.what, "fpp.decode: min_modulation: must be in [0, 1), got -0.250000");
    DecodeOptions o;
    o.max_unwrap_disagreement = 0.75;
    EXPECT_EQ(refusal(o, OptionSpelling::keyword, "fpp.reconstruct").what,
              "fpp.reconstruct: max_unwrap_disagreement: must be in (0, 0.5], got 0.750000");
}

TEST(DecodeOptions, APhaseErrorSettingIsNamedInTheMessage) {
    DecodeOptions o;
    o.phase_error.min_slope = 1.5;
    const std::string rule = "PhaseErrorOptions::min_slope must be in (0, 1), got 1.500000";
    const Refusal flag = refusal(o);
    EXPECT_EQ(flag.field, "decode options: phase_error");
    EXPECT_EQ(flag.what, "command line: decode options: phase_error: " + rule);
    const Refusal keyword = refusal(o, OptionSpelling::keyword, "fpp.decode");
    EXPECT_EQ(keyword.field, "phase_error");
    EXPECT_EQ(keyword.what, "fpp.decode: phase_error: " + rule);
}

} // namespace
