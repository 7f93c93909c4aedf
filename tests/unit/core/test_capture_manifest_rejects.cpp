// Capture manifests that must be refused (firmware/core/formats/capture-set.md):
// one test each, the file and the field named, the error pointing to its line.

#include "capture_manifest_fixtures.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <string>

using fpp::test::expect_rejected;
using fpp::test::kOrigin;
using fpp::test::kValid;
using fpp::test::with;

TEST(CaptureManifestRejects, UnknownFormat) {
    // fpp-capture/2 is known (test_capture_set_v2.cpp); a later version is not.
    expect_rejected(with("fpp-capture/1", "fpp-capture/3"), "format", "fpp-capture/3");
}

TEST(CaptureManifestRejects, MissingFormat) {
    expect_rejected(with("format: fpp-capture/1\n", ""), "format", "missing");
}

TEST(CaptureManifestRejects, UnknownPattern) {
    expect_rejected(with("pattern: white", "pattern: grey"), "sequence[0].pattern", "grey");
}

TEST(CaptureManifestRejects, UnknownAxis) {
    expect_rejected(with("axis: x", "axis: z"), "sequence[1].axis", "z");
}

TEST(CaptureManifestRejects, MissingBlockField) {
    expect_rejected(with("    steps: 3\n", ""), "sequence[1].steps", "missing");
    expect_rejected(with("    bits: 3\n", ""), "sequence[2].bits", "missing");
    expect_rejected(with("  - pattern: white\n", "  - axis: x\n"), "sequence[0].pattern",
                    "missing");
}

TEST(CaptureManifestRejects, MissingTopLevelField) {
    expect_rejected(with("camera:    {width: 16, height: 12}\n", ""), "camera", "missing");
    expect_rejected(with("{width: 16, height: 12}", "{width: 16}"), "camera.height", "missing");
    expect_rejected(with("projector: {width: 64, height: 40}\n", ""), "projector", "missing");
    expect_rejected(
        with("frames: [f0.png, f1.png, f2.png, f3.png, f4.png, f5.png, f6.png, f7.png]\n", ""),
        "frames", "missing");
}

TEST(CaptureManifestRejects, FrameCountMismatch) {
    expect_rejected(with(", f7.png]", "]"), "frames", "7 frames listed");
    expect_rejected(with(", f7.png]", ", f7.png, f8.png]"), "frames", "9 frames listed");
}

TEST(CaptureManifestRejects, NonFiniteNumbers) {
    expect_rejected(with("period: 8.0\n    steps", "period: .nan\n    steps"), "sequence[1].period",
                    "non-finite");
    expect_rejected(with("period: 8.0\n    steps", "period: .inf\n    steps"), "sequence[1].period",
                    "non-finite");
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    phase_offset: -.inf\n"),
                    "sequence[1].phase_offset", "non-finite");
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    phase_offset: nan\n"),
                    "sequence[1].phase_offset", "non-finite");
    expect_rejected(with("period: 8.0\n    steps", "period: 1e999\n    steps"),
                    "sequence[1].period", "out of the double range");
}

TEST(CaptureManifestRejects, NonPositivePeriods) {
    expect_rejected(with("period: 8.0\n    steps", "period: 0\n    steps"), "sequence[1].period",
                    "> 0");
    expect_rejected(with("period: 8.0\n    steps", "period: -8.0\n    steps"), "sequence[1].period",
                    "> 0");
    expect_rejected(with("period: 8.0\n    bits", "period: -8.0\n    bits"), "sequence[2].period",
                    "> 0");
}

TEST(CaptureManifestRejects, FewerThanThreeSteps) {
    // (Fields are checked before the frame count, so the count need not match.)
    expect_rejected(with("steps: 3", "steps: 2"), "sequence[1].steps", "at least 3");
}

TEST(CaptureManifestRejects, ShiftSignOtherThanPlusOrMinusOne) {
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    shift_sign: 0\n"),
                    "sequence[1].shift_sign", "1 or -1");
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    shift_sign: 2\n"),
                    "sequence[1].shift_sign", "1 or -1");
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    shift_sign: -1.0\n"),
                    "sequence[1].shift_sign", "integer");
}

TEST(CaptureManifestRejects, BitsOutOfRange) {
    expect_rejected(with("bits: 3", "bits: 0"), "sequence[2].bits", "between 1 and");
    expect_rejected(with("bits: 3", "bits: 31"), "sequence[2].bits", "between 1 and");
}

TEST(CaptureManifestRejects, GrayBitsTooFewToCoverTheProjector) {
    // 64 projector columns at period 8 are periods 0..7: 3 bits; 2 bits number only 0..3.
    // (One Gray frame fewer: drop one frame name.)
    expect_rejected(with(", f7.png]", "]", with("bits: 3", "bits: 2")), "sequence[2].bits",
                    "at least 3 bits");
    // Exactly covering is fine: 65 columns would need 4 bits, 64 do not.
    EXPECT_NO_THROW(fpp::parse_manifest(kValid, kOrigin));
    expect_rejected(with("{width: 64, height: 40}", "{width: 65, height: 40}"), "sequence[2].bits",
                    "at least 4 bits");
}

TEST(CaptureManifestRejects, GrayPeriodMatchingNoPhaseBlock) {
    expect_rejected(with("period: 8.0\n    bits", "period: 16.0\n    bits"), "sequence[2].period",
                    "not the period of any phase block");
    // A phase block with that period on the other axis does not count.
    expect_rejected(
        with("axis: x\n    period: 8.0\n    bits", "axis: y\n    period: 8.0\n    bits"),
        "sequence[2].period", "no phase block on this axis");
}

TEST(CaptureManifestRejects, NonIntegerWhereAnIntegerIsNeeded) {
    expect_rejected(with("steps: 3", "steps: 3.5"), "sequence[1].steps", "integer");
    expect_rejected(with("steps: 3", "steps: 3.0"), "sequence[1].steps", "integer");
    expect_rejected(with("steps: 3", "steps: 0x3"), "sequence[1].steps", "integer");
    expect_rejected(with("{width: 16, height: 12}", "{width: 16.5, height: 12}"), "camera.width",
                    "integer");
    expect_rejected(with("bits: 3", "bits: three"), "sequence[2].bits", "integer");
}

TEST(CaptureManifestRejects, WrongYamlTypes) {
    expect_rejected(with("{width: 16, height: 12}", "[16, 12]"), "camera", "must be a map");
    expect_rejected(with("frames: [f0.png, f1.png, f2.png, f3.png, f4.png, f5.png, f6.png, f7.png]",
                         "frames: {f0: f0.png}"),
                    "frames", "must be a list");
    expect_rejected(with("frames: [f0.png,", "frames: [[f0.png],"), "frames[0]", "must be text");
    expect_rejected(with("  - pattern: white\n", "  - white\n"), "sequence[0]", "must be a map");
    expect_rejected(with("complementary: true", "complementary: yes"), "sequence[2].complementary",
                    "true or false");
    expect_rejected(with("complementary: true", "complementary: 1"), "sequence[2].complementary",
                    "true or false");
    expect_rejected(with("period: 8.0\n    steps", "period: \"8.0\"\n    steps"),
                    "sequence[1].period", "quoted");
    expect_rejected(with("period: 8.0\n    steps", "period: [8.0]\n    steps"),
                    "sequence[1].period", "must be a number");
    expect_rejected(with("metadata:\n  exposure_us: 8000\n", "metadata: [1, 2]\n"), "metadata",
                    "must be a map");
}

TEST(CaptureManifestRejects, SequenceThatIsNotAList) {
    std::string text = kValid.substr(0, kValid.find("sequence:")) + "sequence: white\n";
    expect_rejected(text, "sequence", "must be a list");
}

TEST(CaptureManifestRejects, EmptySequence) {
    std::string text = kValid.substr(0, kValid.find("sequence:")) + "sequence: []\n";
    expect_rejected(text, "sequence", "at least one");
}

TEST(CaptureManifestRejects, UnknownKeyInsideABlock) {
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    colour: red\n"), "sequence[1].colour",
                    "unknown key");
    // A key of another pattern is unknown here too.
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    bits: 3\n"), "sequence[1].bits",
                    "unknown key");
    expect_rejected(with("  - pattern: white\n", "  - {pattern: white, axis: x}\n"),
                    "sequence[0].axis", "unknown key");
}

TEST(CaptureManifestRejects, UnknownKeyOutsideMetadata) {
    expect_rejected(with("metadata:", "exposure_us: 5\nmetadata:"), "exposure_us", "unknown key");
    expect_rejected(with("{width: 16, height: 12}", "{width: 16, height: 12, depth: 8}"),
                    "camera.depth", "unknown key");
    // Inside metadata anything goes.
    EXPECT_NO_THROW(fpp::parse_manifest(
        with("  exposure_us: 8000\n", "  exposure_us: 8000\n  lens: {f: 12, name: x}\n"), kOrigin));
}

TEST(CaptureManifestRejects, DuplicateKeys) {
    expect_rejected(with("    steps: 3\n", "    steps: 3\n    steps: 3\n"), "sequence[1].steps",
                    "twice");
}

TEST(CaptureManifestRejects, CenterlineWidthNotPositive) {
    const std::string base = with(
        "  - pattern: white\n", "  - {pattern: centerline, axis: y, position: 20.0, width: 1.0}\n");
    EXPECT_NO_THROW(fpp::parse_manifest(base, kOrigin));
    expect_rejected(with("width: 1.0", "width: 0", base), "sequence[0].width", "> 0");
    expect_rejected(with("width: 1.0", "width: -2", base), "sequence[0].width", "> 0");
    expect_rejected(with("position: 20.0, ", "", base), "sequence[0].position", "missing");
}

TEST(CaptureManifestRejects, CenterlineOutsideTheProjector) {
    const std::string base = with(
        "  - pattern: white\n", "  - {pattern: centerline, axis: y, position: 41.0, width: 1.0}\n");
    // Rows 0..39: a line at 41 +- 0.5 lights nothing; one at 40 +- 1 lights row 39.
    expect_rejected(base, "sequence[0].position", "lights no pixel");
    EXPECT_NO_THROW(fpp::parse_manifest(
        with("position: 41.0, width: 1.0", "position: 40.0, width: 2.0", base), kOrigin));
}

TEST(CaptureManifestRejects, NonPositiveCameraOrProjectorSize) {
    expect_rejected(with("{width: 16, height: 12}", "{width: 0, height: 12}"), "camera.width",
                    "between 1 and");
    expect_rejected(with("{width: 16, height: 12}", "{width: 16, height: -12}"), "camera.height",
                    "between 1 and");
    expect_rejected(with("{width: 64, height: 40}", "{width: 64, height: -5}"), "projector.height",
                    "between 1 and");
}

TEST(CaptureManifestRejects, FramePathsOutsideTheFolderOrRepeated) {
    expect_rejected(with("[f0.png,", "[/tmp/f0.png,"), "frames[0]", "relative");
    expect_rejected(with("[f0.png,", "[../f0.png,"), "frames[0]", "inside");
    expect_rejected(with(" f3.png,", " f1.png,"), "frames[3]", "listed twice");
    expect_rejected(with(" f3.png,", " ./f1.png,"), "frames[3]", "listed twice");
    expect_rejected(with(" f3.png,", " capture.yaml,"), "frames[3]", "manifest");
}

TEST(CaptureManifestRejects, TruthWithUnknownKeysOrNoFile) {
    expect_rejected(with("metadata:", "truth: {xyz: t.tiff, depth: d.tiff}\nmetadata:"),
                    "truth.depth", "unknown key");
    expect_rejected(with("metadata:", "truth: {}\nmetadata:"), "truth", "lists no file");
    expect_rejected(with("metadata:", "truth: {xyz: f2.png}\nmetadata:"), "truth.xyz",
                    "also frames[2]");
}

TEST(CaptureManifestRejects, YamlSyntaxErrorNamesFileAndLine) {
    try {
        fpp::parse_manifest(with("steps: 3", "steps: [3"), kOrigin);
        FAIL() << "accepted";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), kOrigin);
        EXPECT_NE(std::string(e.what()).find("line"), std::string::npos) << e.what();
    }
    expect_rejected("- just\n- a list\n", "", "must be a YAML map");
}

TEST(CaptureManifestRejects, ErrorsPointToTheLine) {
    try {
        fpp::parse_manifest(with("steps: 3", "steps: 2"), kOrigin);
        FAIL() << "accepted";
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("(line 10)"), std::string::npos) << e.what();
    }
}
