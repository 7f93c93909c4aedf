// fpp-capture/2 (firmware/core/formats/capture-set.md): every new field read,
// written and read back bit-exactly; ratio periods and fringe counts; v2
// fields refused in v1 files; a table of broken sets each naming its field;
// BMP and TIFF frames inside a set; bits in use declared or found.

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/yaml_fields.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <variant>
#include <vector>

namespace fs = std::filesystem;
using fpp::test::TempDir;

namespace {

const fs::path kOrigin = "/captures/v2/capture.yaml";

// "[f0.png, ..., f{n-1}.png]"
std::string frame_list(int n) {
    std::string s = "[";
    for (int i = 0; i < n; ++i)
        s += (i ? ", f" : "f") + std::to_string(i) + ".png";
    return s + "]";
}

// A v2 manifest: 16x12 camera, 64x40 projector, the given blocks and frame count.
std::string manifest(const std::string& blocks, int frames, const std::string& extra = "",
                     const std::string& format = "fpp-capture/2") {
    return "format: " + format +
           "\ncamera: {width: 16, height: 12}\nprojector: {width: 64, height: 40}\n" + extra +
           "frames: " + frame_list(frames) + "\nsequence:\n" + blocks;
}

const std::string kWhiteBlack = "  - {pattern: white}\n  - {pattern: black}\n";

template <class F>
void expect_input_error(F&& f, const fs::path& file, const std::string& field,
                        const std::string& hint) {
    try {
        f();
        ADD_FAILURE() << "accepted; expected a rejection of " << field << " (" << hint << ")";
    } catch (const fpp::InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.file(), file) << what;
        EXPECT_EQ(e.field(), field) << what;
        EXPECT_NE(what.find(hint), std::string::npos) << what;
    }
}

void expect_rejected(const std::string& yaml, const std::string& field, const std::string& hint) {
    expect_input_error([&] { fpp::parse_manifest(yaml, kOrigin); }, kOrigin, field, hint);
}

fpp::Frame frame16(fpp::Size size, std::uint16_t largest) {
    fpp::Frame f;
    f.bit_depth = 16;
    f.u16 = fpp::Image<std::uint16_t>(size);
    for (std::size_t i = 0; i < f.u16.storage().size(); ++i) {
        f.u16.storage()[i] = static_cast<std::uint16_t>((i * 7) % (std::size_t{largest} + 1));
    }
    f.u16.storage()[3] = largest;
    return f;
}

// A code-only set on disk (white, black, 3-bit Gray on x) with the given frames.
fs::path write_code_set(const TempDir& dir, const std::string& name,
                        const std::vector<fpp::Frame>& frames, int bit_depth = 0) {
    fpp::CaptureManifest m = fpp::parse_manifest(
        manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 8.0, bits: 3}\n", 5), kOrigin);
    fpp::write_capture_set(dir / name, m, frames);
    if (bit_depth != 0) { // by hand: the writer refuses a bit_depth its frames contradict
        const fs::path yaml = dir / name / "capture.yaml";
        std::string text = fpp::yaml_fields::read_text_file(yaml);
        text.insert(text.find("frames:"), "bit_depth: " + std::to_string(bit_depth) + "\n");
        std::ofstream(yaml, std::ios::binary) << text;
    }
    return dir / name;
}

} // namespace

TEST(CaptureSetV2, EveryNewFieldRoundTripsBitExactly) {
    const std::string yaml = manifest(
        kWhiteBlack +
            "  - {pattern: phase, axis: x, period: 1920/58, steps: 4, shift_sign: -1}\n"
            "  - {pattern: gray, axis: x, period: 1920/58, bits: 2, offset_periods: 0.5,"
            " order: lsb_first}\n"
            "  - {pattern: phase, axis: y, period: 10.0, shifting: two_plus_one}\n"
            "  - {pattern: phase, axis: y, period: 7.5, steps: 3, shifting: modulated,"
            " carrier_period: 64/9, carrier_steps: 4}\n"
            "  - {pattern: micro_phase, axis: x, periods: [14.0, 29/2, 15.0], phase_offset: 0.25}\n"
            "  - {pattern: gray, axis: y, period: 3.0, bits: 3, code: binary, levels: 4,"
            " offset: -1.5, inverse: true}\n",
        2 + 4 + 2 + 3 + 12 + 5 + 6, "bit_depth: 12\n");
    const fpp::CaptureManifest m = fpp::parse_manifest(yaml, kOrigin);
    const auto& phase = std::get<fpp::PhaseBlock>(m.sequence[2]);
    EXPECT_EQ(phase.period, 1920.0 / 58.0); // exact double division
    const auto& shifted = std::get<fpp::GrayBlock>(m.sequence[3]);
    EXPECT_EQ(shifted.offset, 0.5 * (1920.0 / 58.0));
    EXPECT_EQ(shifted.order, fpp::DigitOrder::lsb_first);
    const auto& two = std::get<fpp::PhaseBlock>(m.sequence[4]);
    EXPECT_EQ(two.shifting, fpp::PhaseShifting::two_plus_one);
    EXPECT_EQ(two.steps, 3);
    const auto& modulated = std::get<fpp::PhaseBlock>(m.sequence[5]);
    EXPECT_EQ(modulated.carrier_period, 64.0 / 9.0);
    EXPECT_EQ(modulated.carrier_steps, 4);
    const auto& micro = std::get<fpp::MicroPhaseBlock>(m.sequence[6]);
    EXPECT_EQ(micro.periods, (std::vector<double>{14.0, 14.5, 15.0}));
    const auto& quaternary = std::get<fpp::GrayBlock>(m.sequence[7]);
    EXPECT_EQ(quaternary.code, fpp::CodeKind::binary);
    EXPECT_EQ(quaternary.levels, 4);
    EXPECT_EQ(quaternary.offset, -1.5);
    EXPECT_EQ(m.bit_depth, 12);

    const std::string written = fpp::manifest_to_yaml(m);
    EXPECT_EQ(written.rfind("format: fpp-capture/2\n", 0), 0u) << written;
    EXPECT_NE(written.find("bit_depth: 12\n"), std::string::npos) << written;
    EXPECT_NE(written.find("    shifting: standard\n"), std::string::npos) << written; // defaults
    EXPECT_NE(written.find("    levels: 2\n"), std::string::npos) << written;
    EXPECT_NE(written.find("    periods: [14.0, 14.5, 15.0]\n"), std::string::npos) << written;
    EXPECT_EQ(fpp::parse_manifest(written, kOrigin), m) << written;
}

// SLStudio's micro codec inverts every other extra frequency: one offset per
// period after the first, written back only when given.
TEST(CaptureSetV2, MicroPhaseExtraOffsetsRoundTrip) {
    const fpp::CaptureManifest m = fpp::parse_manifest(
        manifest("  - {pattern: micro_phase, axis: x, periods: [14.0, 29/2, 15.0],"
                 " extra_phase_offsets: [3.141592653589793, -0.5]}\n",
                 5),
        kOrigin);
    const auto& micro = std::get<fpp::MicroPhaseBlock>(m.sequence[0]);
    EXPECT_EQ(micro.extra_phase_offsets, (std::vector<double>{3.141592653589793, -0.5}));
    const std::string written = fpp::manifest_to_yaml(m);
    EXPECT_NE(written.find("    extra_phase_offsets: [3.141592653589793, -0.5]\n"),
              std::string::npos)
        << written;
    EXPECT_EQ(fpp::parse_manifest(written, kOrigin), m) << written;

    fpp::CaptureManifest plain = m;
    std::get<fpp::MicroPhaseBlock>(plain.sequence[0]).extra_phase_offsets.clear();
    const std::string plain_text = fpp::manifest_to_yaml(plain);
    EXPECT_EQ(plain_text.find("extra_phase_offsets"), std::string::npos) << plain_text;
    EXPECT_EQ(fpp::parse_manifest(plain_text, kOrigin), plain) << plain_text;
}

TEST(CaptureSetV2, VersionOneManifestsAreStillWrittenAsVersionOne) {
    const fpp::CaptureManifest m =
        fpp::parse_manifest(manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3}\n"
                                     "  - {pattern: gray, axis: x, period: 8.0, bits: 3}\n",
                                     6, "", "fpp-capture/1"),
                            kOrigin);
    const std::string written = fpp::manifest_to_yaml(m);
    EXPECT_EQ(written.rfind("format: fpp-capture/1\n", 0), 0u);
    EXPECT_EQ(written.find("shifting"), std::string::npos) << written;
    EXPECT_EQ(written.find("levels"), std::string::npos) << written;
    // The same blocks read from a v2 file are the same manifest.
    const fpp::CaptureManifest v2 =
        fpp::parse_manifest(manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3}\n"
                                     "  - {pattern: gray, axis: x, period: 8.0, bits: 3}\n",
                                     6),
                            kOrigin);
    EXPECT_EQ(v2, m);
}

TEST(CaptureSetV2, FringesAndRatiosGiveTheExactPeriod) {
    const std::string blocks = "  - {pattern: phase, axis: x, fringes: 58, steps: 3}\n"
                               "  - {pattern: phase, axis: y, fringes: 2.5, steps: 3}\n";
    std::string yaml = manifest(blocks, 6);
    yaml.replace(yaml.find("{width: 64, height: 40}"), 23, "{width: 1920, height: 1080}");
    const fpp::CaptureManifest m = fpp::parse_manifest(yaml, kOrigin);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(m.sequence[0]).period, 1920.0 / 58.0);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(m.sequence[1]).period, 1080.0 / 2.5);
    const fpp::CaptureManifest again = fpp::parse_manifest(fpp::manifest_to_yaml(m), kOrigin);
    EXPECT_EQ(again, m);
    // A sequence file has no projector to count fringes across.
    expect_input_error(
        [] {
            fpp::parse_sequence("sequence:\n  - {pattern: phase, axis: x, fringes: 58, steps: 3}\n",
                                "scan.yaml");
        },
        "scan.yaml", "sequence[0].fringes", "projector size");
    // Sequence files accept the other v2 forms.
    const fpp::Sequence s = fpp::parse_sequence(
        "sequence:\n  - {pattern: white}\n  - {pattern: black}\n"
        "  - {pattern: gray, axis: y, period: 1080/64, bits: 6, code: binary}\n",
        "scan.yaml");
    EXPECT_EQ(std::get<fpp::GrayBlock>(s[2]).period, 1080.0 / 64.0);
}

TEST(CaptureSetV2, BrokenManifestsNameTheirField) {
    struct Case {
        std::string yaml;
        std::string field;
        std::string hint;
    };
    const std::string gray_only = "  - {pattern: gray, axis: x, period: 8.0, bits: 3}\n";
    const std::vector<Case> cases = {
        // v2 fields in a v1 file.
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3, shifting: standard}\n", 3,
                  "", "fpp-capture/1"),
         "sequence[0].shifting", "needs format: fpp-capture/2"},
        {manifest("  - {pattern: phase, axis: x, period: 64/8, steps: 3}\n", 3, "",
                  "fpp-capture/1"),
         "sequence[0].period", "needs format: fpp-capture/2"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [9.0, 10.0]}\n", 4, "",
                  "fpp-capture/1"),
         "sequence[0].pattern", "needs format: fpp-capture/2"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3}\n", 3, "bit_depth: 12\n",
                  "fpp-capture/1"),
         "bit_depth", "needs format: fpp-capture/2"},
        {manifest(kWhiteBlack + gray_only, 5, "", "fpp-capture/1"), "sequence[2].period",
         "needs format: fpp-capture/2"},
        // Unknown format, pattern kinds and enumerations.
        {manifest(gray_only, 3, "", "fpp-capture/3"), "format", "fpp-capture/2"},
        {manifest("  - {pattern: stripes}\n", 1), "sequence[0].pattern", "micro_phase"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3, shifting: double}\n", 3),
         "sequence[0].shifting", "two_plus_one"},
        {manifest(kWhiteBlack +
                      "  - {pattern: gray, axis: x, period: 8.0, bits: 3, code: ternary}\n",
                  5),
         "sequence[2].code", "gray, binary"},
        {manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 8.0, bits: 3, order: up}\n",
                  5),
         "sequence[2].order", "lsb_first"},
        // Wrong counts.
        {manifest(kWhiteBlack + gray_only, 6), "frames", "add up to 5"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, shifting: modulated, steps: 3,"
                  " carrier_period: 5.0, carrier_steps: 3}\n",
                  3),
         "frames", "add up to 9"},
        // Code without a threshold reference; levels > 2 without white/black.
        {manifest(gray_only, 3), "sequence[0].period", "threshold reference"},
        {manifest("  - {pattern: white}\n" + gray_only, 4), "sequence[1].period",
         "threshold reference"},
        {manifest("  - {pattern: gray, axis: x, period: 8.0, bits: 2, levels: 3, inverse: true}\n",
                  4),
         "sequence[0].levels", "white and a black block"},
        // ... nor a phase block of its period to scale it (SLMaster's interzone
        // code has one: tests/integration/core/test_decode_families.cpp).
        {manifest("  - {pattern: phase, axis: x, period: 16.0, steps: 3}\n"
                  "  - {pattern: gray, axis: x, period: 8.0, bits: 2, levels: 4}\n",
                  5),
         "sequence[1].levels", "or a phase block of its period on its axis"},
        {manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 8.0, bits: 3, code: binary,"
                                " complementary: true}\n",
                  6),
         "sequence[2].complementary", "code gray and levels 2"},
        {manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 8.0, bits: 1, levels: 1}\n",
                  3),
         "sequence[2].levels", "at least 2"},
        {manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 8.0, bits: 16, levels: 4}\n",
                  18),
         "sequence[2].levels", "at most 2^30"},
        // Periods that do not fit the projector.
        {manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 8.0, bits: 3, offset: 4.0}\n",
                  5),
         "sequence[2].bits", "code steps -1.0 to 7.0"},
        {manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 4.0, bits: 2, levels: 3}\n",
                  4),
         "sequence[2].bits", "at least 3 bits"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [16.0, 64.0]}\n", 4),
         "sequence[0].periods[1]", "below the projector's 64 columns"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [16.0, 16.0]}\n", 4),
         "sequence[0].periods[1]", "distinct"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [16.0]}\n", 3),
         "sequence[0].periods", "at least 2"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [9.0, 10.0, 11.0],"
                  " extra_phase_offsets: [3.0]}\n",
                  5),
         "sequence[0].extra_phase_offsets", "one offset per period after the first (2), got 1"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [9.0, 10.0],"
                  " extra_phase_offsets: [pi]}\n",
                  4),
         "sequence[0].extra_phase_offsets[0]", "must be a number, got 'pi'"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [9.0, 10.0],"
                  " extra_phase_offsets: [.nan]}\n",
                  4),
         "sequence[0].extra_phase_offsets[0]", "non-finite"},
        {manifest("  - {pattern: micro_phase, axis: x, periods: [9.0, 10.0],"
                  " extra_phase_offsets: 3.0}\n",
                  4),
         "sequence[0].extra_phase_offsets", "must be a list"},
        {manifest("  - {pattern: phase, axis: x, period: 8/0, steps: 3}\n", 3),
         "sequence[0].period", "divides by zero"},
        {manifest("  - {pattern: phase, axis: x, period: 8/x, steps: 3}\n", 3),
         "sequence[0].period", "ratio of two numbers"},
        {manifest("  - {pattern: phase, axis: x, period: .inf, steps: 3}\n", 3),
         "sequence[0].period", "non-finite"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, fringes: 8, steps: 3}\n", 3),
         "sequence[0].fringes", "not both"},
        {manifest("  - {pattern: phase, axis: x, fringes: 0, steps: 3}\n", 3),
         "sequence[0].fringes", "must be > 0"},
        {manifest("  - {pattern: phase, axis: x, steps: 3}\n", 3), "sequence[0].period",
         "period or fringes"},
        // Phase variants.
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 4, shifting: two_plus_one}\n",
                  3),
         "sequence[0].steps", "exactly 3 frames"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3, shifting: modulated,"
                  " carrier_steps: 3}\n",
                  9),
         "sequence[0].carrier_period", "missing field"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3, shifting: modulated,"
                  " carrier_period: 6.0, carrier_steps: 2}\n",
                  6),
         "sequence[0].carrier_steps", "at least 3"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3, carrier_steps: 3}\n", 3),
         "sequence[0].carrier_steps", "only with shifting: modulated"},
        {manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 8.0, bits: 3, offset: 1.0,"
                                " offset_periods: 0.5}\n",
                  5),
         "sequence[2].offset_periods", "not both"},
        {manifest("  - {pattern: phase, axis: x, period: 8.0, steps: 3}\n", 3, "bit_depth: 17\n"),
         "bit_depth", "9 to 16"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.yaml);
        expect_rejected(c.yaml, c.field, c.hint);
    }
}

TEST(CaptureSetV2, CodeOnlySetsAreAccepted) {
    // Inverse frames alone are a threshold reference for a binary code...
    EXPECT_NO_THROW(fpp::parse_manifest(
        manifest("  - {pattern: gray, axis: x, period: 8.0, bits: 3, inverse: true}\n", 6),
        kOrigin));
    // ...and white + black for any code; a shift of half a step that needs one more step.
    const fpp::CaptureManifest m = fpp::parse_manifest(
        manifest(kWhiteBlack +
                     "  - {pattern: gray, axis: x, period: 8.0, bits: 4, offset_periods: 1/2}\n",
                 6),
        kOrigin);
    EXPECT_EQ(std::get<fpp::GrayBlock>(m.sequence[2]).offset, 4.0);
    // Quaternary: 64 columns at period 4 are 16 steps, 2 digits of 4 levels.
    EXPECT_NO_THROW(fpp::parse_manifest(
        manifest(kWhiteBlack + "  - {pattern: gray, axis: x, period: 4.0, bits: 2, levels: 4}\n",
                 4),
        kOrigin));
}

TEST(CaptureSetV2, BitsInUseAreFoundFromTheFrames) {
    TempDir dir;
    const fpp::Size camera{16, 12};
    struct Case {
        std::uint16_t largest;
        int bits;
    };
    for (const Case c : {Case{200, 9}, Case{511, 9}, Case{512, 10}, Case{1023, 10}, Case{4095, 12},
                         Case{4096, 14}, Case{16383, 14}, Case{40000, 16}}) {
        std::vector<fpp::Frame> frames(5, frame16(camera, 100));
        frames[2] = frame16(camera, c.largest);
        std::string name = "s";
        name += std::to_string(c.largest);
        const fs::path folder = write_code_set(dir, name, frames);
        const fpp::CaptureSet set = fpp::read_capture_set(folder);
        EXPECT_EQ(set.bits_in_use, c.bits) << c.largest;
        EXPECT_EQ(set.bits_source, fpp::BitsInUseSource::found);
        for (const auto& f : set.frames) {
            EXPECT_EQ(f.significant_bits, c.bits);
            EXPECT_EQ(f.max_value(), (1 << c.bits) - 1);
        }
    }
    // 8-bit frames: the container's 8 bits.
    std::vector<fpp::Frame> eight(5);
    for (auto& f : eight)
        f.u8 = fpp::Image<std::uint8_t>(camera, 1, 255);
    const fpp::CaptureSet set8 = fpp::read_capture_set(write_code_set(dir, "eight", eight));
    EXPECT_EQ(set8.bits_in_use, 8);
    EXPECT_EQ(set8.bits_source, fpp::BitsInUseSource::container);
    EXPECT_EQ(set8.frames[0].max_value(), 255);
}

TEST(CaptureSetV2, DeclaredBitDepthIsCheckedAgainstEveryFrame) {
    TempDir dir;
    const fpp::Size camera{16, 12};
    std::vector<fpp::Frame> frames(5, frame16(camera, 4095));
    const fpp::CaptureSet ok = fpp::read_capture_set(write_code_set(dir, "ok", frames, 12));
    EXPECT_EQ(ok.bits_in_use, 12);
    EXPECT_EQ(ok.bits_source, fpp::BitsInUseSource::declared);
    EXPECT_EQ(ok.frames[4].significant_bits, 12);
    // Declaring more than the frames use is the author's call: 14 stays 14.
    EXPECT_EQ(fpp::read_capture_set(write_code_set(dir, "wide", frames, 14)).bits_in_use, 14);

    frames[3] = frame16(camera, 4096);
    const fs::path over = write_code_set(dir, "over", frames, 12);
    expect_input_error([&] { fpp::read_capture_set(over); }, over / "f3.png", "frames[3]",
                       "above the largest of bit_depth 12 (4095)");

    std::vector<fpp::Frame> eight(5);
    for (auto& f : eight)
        f.u8 = fpp::Image<std::uint8_t>(camera);
    const fs::path eight12 = write_code_set(dir, "eight12", eight, 12);
    expect_input_error([&] { fpp::read_capture_set(eight12); }, eight12 / "capture.yaml",
                       "bit_depth", "needs 16-bit frames");
    const fs::path sixteen8 =
        write_code_set(dir, "sixteen8", std::vector<fpp::Frame>(5, frame16(camera, 9)), 8);
    expect_input_error([&] { fpp::read_capture_set(sixteen8); }, sixteen8 / "capture.yaml",
                       "bit_depth", "give 9 to 16");
}

TEST(CaptureSetV2, FramesMayBeBmpOrTiffButNotMixedDepths) {
    TempDir dir;
    const fpp::Size camera{16, 12};
    std::vector<fpp::Frame> frames(5);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        frames[i].u8 = fpp::Image<std::uint8_t>(camera, 1, static_cast<std::uint8_t>(40 * i));
    }
    const fs::path folder = write_code_set(dir, "mixed", frames);
    // f1 becomes a 24-bit BMP of the same grey (name unchanged: magic decides).
    {
        const int stride = (16 * 3 + 3) / 4 * 4;
        std::vector<char> bmp(54 + std::size_t(stride) * 12, 40);
        auto put32 = [&](std::size_t at, std::uint32_t v) {
            for (int k = 0; k < 4; ++k)
                bmp[at + std::size_t(k)] = static_cast<char>(v >> (8 * k));
        };
        bmp[0] = 'B';
        bmp[1] = 'M';
        put32(2, static_cast<std::uint32_t>(bmp.size()));
        put32(6, 0);
        put32(10, 54);
        put32(14, 40);
        put32(18, 16);
        put32(22, 12);
        put32(26, 1 | (24 << 16));
        put32(30, 0);
        put32(34, 0);
        put32(38, 0);
        put32(42, 0);
        put32(46, 0);
        put32(50, 0);
        std::ofstream(folder / "f1.png", std::ios::binary)
            .write(bmp.data(), std::streamsize(bmp.size()));
    }
    const fpp::CaptureSet set = fpp::read_capture_set(folder);
    EXPECT_EQ(set.frames[1].u8.at(15, 11), 40);
    EXPECT_EQ(set.frames[4].u8.at(0, 0), 160);

    // A 16-bit frame among 8-bit ones is refused naming it.
    fpp::write_png(folder / "f4.png", frame16(camera, 1000));
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / "f4.png", "frames[4]",
                       "16-bit but frames[0] is 8-bit");
}

namespace {

std::string numbered(const std::string& stem, int count, const std::string& ext) {
    std::string s = "[";
    for (int i = 0; i < count; ++i) {
        std::string n = std::to_string(i);
        if (n.size() < 2)
            n.insert(0, "0");
        s += (i ? ", " : "") + stem + n + ext;
    }
    return s + "]";
}

} // namespace

TEST(CaptureSetV2, TheSpecExamplesRead) {
    // firmware/core/formats/capture-set.md, "Examples", with their frame lists written out.
    const fpp::CaptureManifest sl =
        fpp::parse_manifest("format: fpp-capture/2\ncamera: {width: 1280, height: 1024}\n"
                            "projector: {width: 1280, height: 800}\nframes: " +
                                numbered("frameSeq_", 18, ".bmp") +
                                "\nsequence:\n  - pattern: white\n  - pattern: black\n"
                                "  - {pattern: gray, axis: x, period: 2, bits: 10}\n"
                                "  - {pattern: gray, axis: y, period: 16, bits: 6}\n",
                            kOrigin);
    EXPECT_EQ(fpp::frame_count(sl.sequence), 18);

    std::string opencv_frames = "[";
    for (int i = 0; i < 40; i += 2) {
        opencv_frames += "p";
        opencv_frames += std::to_string(i + 1);
        opencv_frames += ".png, p";
        opencv_frames += std::to_string(i);
        opencv_frames += ".png, ";
    }
    opencv_frames += "white.png, black.png]";
    const fpp::CaptureManifest cv = fpp::parse_manifest(
        "format: fpp-capture/2\ncamera: {width: 1280, height: 960}\n"
        "projector: {width: 1024, height: 768}\nframes: " +
            opencv_frames +
            "\nsequence:\n  - {pattern: gray, axis: x, period: 1, bits: 10, inverse: true}\n"
            "  - {pattern: gray, axis: y, period: 1, bits: 10, inverse: true}\n"
            "  - pattern: white\n  - pattern: black\n",
        kOrigin);
    EXPECT_EQ(cv.frames.size(), 42u);

    const std::string shift_gray =
        "format: fpp-capture/2\ncamera: {width: 1600, height: 1200}\n"
        "projector: {width: 1280, height: 720}\nframes: " +
        numbered("", 12, ".bmp") +
        "\nsequence:\n  - pattern: white\n  - pattern: black\n"
        "  - {pattern: phase, axis: x, fringes: 32, steps: 4}\n"
        "  - {pattern: gray, axis: x, period: 1280/32, bits: 6, offset_periods: 1/2}\n";
    const fpp::CaptureManifest sm = fpp::parse_manifest(shift_gray, kOrigin);
    EXPECT_EQ(std::get<fpp::GrayBlock>(sm.sequence[3]).offset, 20.0);
    // One bit fewer cannot number the 33 steps the shifted code touches.
    std::string five_bits = shift_gray;
    five_bits.replace(five_bits.find("bits: 6"), 7, "bits: 5");
    five_bits.replace(five_bits.find(", 11.bmp"), 8, "");
    expect_rejected(five_bits, "sequence[3].bits", "-1.0 to 31.0 (33.0)");
    // SLMaster's shift-Gray: offset -P/2 and 5 bits; its 33 steps fit with
    // wrap (the last repeats step 0's codeword), and wrap is written back.
    std::string wrapping = five_bits;
    wrapping.replace(wrapping.find("offset_periods: 1/2"), 19, "offset_periods: -1/2, wrap: true");
    const fpp::CaptureManifest wm = fpp::parse_manifest(wrapping, kOrigin);
    EXPECT_TRUE(std::get<fpp::GrayBlock>(wm.sequence[3]).wrap);
    EXPECT_EQ(std::get<fpp::GrayBlock>(wm.sequence[3]).offset, -20.0);
    EXPECT_EQ(fpp::parse_manifest(fpp::manifest_to_yaml(wm), kOrigin).sequence, wm.sequence);
    std::string no_wrap = wrapping;
    no_wrap.replace(no_wrap.find(", wrap: true"), 12, "");
    expect_rejected(no_wrap, "sequence[3].bits", "0.0 to 32.0 (33.0)");
    // A code-only block cannot tell its last step from its first.
    std::string code_only = wrapping;
    code_only.replace(code_only.find("period: 1280/32"), 15, "period: 41");
    expect_rejected(code_only, "sequence[3].wrap", "needs a phase block of its period");

    const fpp::CaptureManifest twelve = fpp::parse_manifest(
        "format: fpp-capture/2\ncamera: {width: 2448, height: 2048}\n"
        "projector: {width: 1920, height: 1080}\nbit_depth: 12\nframes: " +
            numbered("", 12, ".tif") +
            "\nsequence:\n  - {pattern: phase, axis: x, period: 1920/58, steps: 8}\n"
            "  - {pattern: phase, axis: x, fringes: 1, steps: 4}\n",
        kOrigin);
    EXPECT_EQ(twelve.bit_depth, 12);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(twelve.sequence[1]).period, 1920.0);
}

TEST(CaptureSetV2, MutatedManifestsGiveNamedErrorsOnly) {
    // Deterministic mutations of a valid v2 manifest: each either reads or is
    // refused with an InputError naming the file; nothing else escapes.
    const std::string valid = manifest(
        kWhiteBlack + "  - {pattern: phase, axis: x, period: 64/8, steps: 3}\n"
                      "  - {pattern: gray, axis: x, period: 8.0, bits: 4, offset_periods: 1/2,"
                      " levels: 2, code: gray}\n"
                      "  - {pattern: micro_phase, axis: y, periods: [9.0, 10.0]}\n",
        2 + 3 + 4 + 4, "bit_depth: 12\n");
    ASSERT_NO_THROW(fpp::parse_manifest(valid, kOrigin));
    const std::string alphabet = "0123456789-./:{}[],# \nabxyz";
    std::uint32_t state = 12345;
    auto next = [&state] {
        state = state * 1664525u + 1013904223u;
        return state >> 8;
    };
    int refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        std::string text = valid;
        const int edits = 1 + static_cast<int>(next() % 3);
        for (int e = 0; e < edits; ++e) {
            const std::size_t at = next() % text.size();
            switch (next() % 3) {
            case 0:
                text[at] = alphabet[next() % alphabet.size()];
                break;
            case 1:
                text.erase(at, 1 + next() % 4);
                break;
            default:
                text.insert(at, 1, alphabet[next() % alphabet.size()]);
                break;
            }
        }
        try {
            fpp::parse_manifest(text, kOrigin);
        } catch (const fpp::InputError& e) {
            ++refused;
            EXPECT_EQ(e.file(), kOrigin) << text;
        } catch (const std::exception& e) {
            ADD_FAILURE() << "unnamed error " << e.what() << " for:\n" << text;
        }
    }
    EXPECT_GT(refused, 1500); // most mutations break something
}
