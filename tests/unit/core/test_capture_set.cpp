// Capture sets (firmware/core/formats/capture-set.md): reading (the manifest
// refusals are in test_capture_manifest_rejects.cpp; every rejection names the
// file and the field), exact writing, atomic folder output, board.yaml, and the
// real capture sets under the shared datasets.

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/yaml_fields.hpp"

#include "capture_manifest_fixtures.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <variant>
#include <vector>

namespace fs = std::filesystem;
using fpp::test::expect_input_error;
using fpp::test::kOrigin;
using fpp::test::kValid;
using fpp::test::TempDir;
using fpp::test::with;

namespace {

fpp::Frame random_frame(fpp::Size size, int depth, std::uint32_t seed) {
    fpp::Frame f;
    f.bit_depth = depth;
    std::mt19937 rng(seed);
    if (depth == 8) {
        f.u8 = fpp::Image<std::uint8_t>(size);
        for (auto& v : f.u8.storage())
            v = static_cast<std::uint8_t>(rng());
    } else {
        f.u16 = fpp::Image<std::uint16_t>(size);
        for (auto& v : f.u16.storage())
            v = static_cast<std::uint16_t>(rng());
    }
    return f;
}

std::vector<fpp::Frame> frames_for(const fpp::CaptureManifest& m, int depth = 8) {
    std::vector<fpp::Frame> frames;
    for (std::size_t i = 0; i < m.frames.size(); ++i) {
        frames.push_back(random_frame(m.camera, depth, static_cast<std::uint32_t>(i + 1)));
    }
    return frames;
}

void expect_same_frames(const std::vector<fpp::Frame>& a, const std::vector<fpp::Frame>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].bit_depth, b[i].bit_depth) << i;
        EXPECT_EQ(a[i].u8.storage(), b[i].u8.storage()) << i;
        EXPECT_EQ(a[i].u16.storage(), b[i].u16.storage()) << i;
    }
}

std::vector<std::string> listing(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

// A valid capture set on disk built from kValid (8-bit frames).
fs::path make_set(const TempDir& dir, const std::string& name = "set") {
    const auto m = fpp::parse_manifest(kValid, kOrigin);
    const fs::path folder = dir / name;
    fpp::write_capture_set(folder, m, frames_for(m));
    return folder;
}

} // namespace

// ---------------------------------------------------------------------------
// Reading valid manifests
// ---------------------------------------------------------------------------

TEST(CaptureManifest, ParsesBlockStyleWithDefaults) {
    const auto m = fpp::parse_manifest(kValid, kOrigin);
    EXPECT_EQ(m.camera, (fpp::Size{16, 12}));
    EXPECT_EQ(m.projector, (fpp::Size{64, 40}));
    ASSERT_EQ(m.frames.size(), 8u);
    EXPECT_EQ(m.frames[7], "f7.png");
    ASSERT_EQ(m.sequence.size(), 3u);
    EXPECT_TRUE(std::holds_alternative<fpp::WhiteBlock>(m.sequence[0]));
    const auto& p = std::get<fpp::PhaseBlock>(m.sequence[1]);
    EXPECT_EQ(p.axis, fpp::Axis::x);
    EXPECT_EQ(p.period, 8.0);
    EXPECT_EQ(p.steps, 3);
    EXPECT_EQ(p.shift_sign, 1);     // default
    EXPECT_EQ(p.phase_offset, 0.0); // default
    const auto& g = std::get<fpp::GrayBlock>(m.sequence[2]);
    EXPECT_EQ(g.bits, 3);
    EXPECT_TRUE(g.complementary);
    EXPECT_FALSE(g.inverse); // default
    EXPECT_EQ(m.metadata_yaml, "exposure_us: 8000");
    EXPECT_FALSE(m.truth.has_value());
}

TEST(CaptureManifest, FlowAndBlockStylesAreEquivalent) {
    const std::string flow = R"(format: fpp-capture/1
camera: {width: 16, height: 12}
projector: {width: 64, height: 40}
frames: [f0.png, f1.png, f2.png, f3.png,
         f4.png, f5.png, f6.png, f7.png]
sequence:
  - {pattern: white}
  - {pattern: phase, axis: x, period: 8, steps: 3, shift_sign: +1, phase_offset: 0.0}
  - {pattern: gray,  axis: x, period: 8.0, bits: 3, complementary: true, inverse: false}
metadata: {exposure_us: 8000}
)";
    auto a = fpp::parse_manifest(flow, kOrigin);
    auto b = fpp::parse_manifest(kValid, kOrigin);
    EXPECT_EQ(a.sequence, b.sequence);
    EXPECT_EQ(a.frames, b.frames);
    EXPECT_EQ(a.metadata_yaml, "{exposure_us: 8000}"); // kept in its own style
}

TEST(CaptureManifest, ParsesTheSpecExample) {
    // The example of firmware/core/formats/capture-set.md with its comments, frames adjusted to
    // the block count (1 + 1 + 8 + 7 + 1 = 18).
    const std::string spec = R"(format: fpp-capture/1
camera:    {width: 1600, height: 1200}
projector: {width: 1280, height: 800}
frames: [000.png, 001.png, 002.png, 003.png, 004.png, 005.png, 006.png, 007.png, 008.png,
         009.png, 010.png, 011.png, 012.png, 013.png, 014.png, 015.png, 016.png, 017.png]
sequence:                             # pattern blocks in capture order
  - pattern: white                    # 1 frame: projector full on (texture image)
  - pattern: black                    # 1 frame: projector full off
  - pattern: phase                    # `steps` frames
    axis: x                           # x: intensity varies along projector columns
    period: 20.0                      # projector pixels per fringe period (real)
    steps: 8                          # N >= 3
    shift_sign: 1                     # +1 or -1 (see below); default +1
    phase_offset: 0.0                 # radians; default 0
  - pattern: gray                     # Gray-code bit planes, MSB first
    axis: x
    period: 20.0                      # the phase block's period it indexes
    bits: 6                           # floor(p/period) is coded on `bits` bits
    complementary: true               # default false; adds one frame (see below)
    inverse: false                    # default false
  - pattern: centerline               # 1 frame: one bright line
    axis: x
    position: 640.0                   # projector coordinate of the line centre
    width: 1.0                        # line width in projector pixels
metadata:                             # free-form map; readers keep it, never need it
  exposure_us: 8000
)";
    const auto m = fpp::parse_manifest(spec, kOrigin);
    EXPECT_EQ(m.frames.size(), 18u);
    EXPECT_EQ(fpp::frame_count(m.sequence), 18);
    const auto& c = std::get<fpp::CenterlineBlock>(m.sequence[4]);
    EXPECT_EQ(c.position, 640.0);
    EXPECT_EQ(c.width, 1.0);
}

TEST(CaptureManifest, AcceptsSignedAndExponentNumbers) {
    const auto m = fpp::parse_manifest(
        with("    steps: 3\n",
             "    steps: +3\n    shift_sign: -1\n    phase_offset: -3.141592653589793e0\n"),
        kOrigin);
    const auto& p = std::get<fpp::PhaseBlock>(m.sequence[1]);
    EXPECT_EQ(p.steps, 3);
    EXPECT_EQ(p.shift_sign, -1);
    EXPECT_EQ(p.phase_offset, -3.141592653589793);
}

TEST(CaptureManifest, ReadsFromFileAndNamesMissingFile) {
    TempDir dir;
    write_text(dir / "capture.yaml", kValid);
    EXPECT_EQ(fpp::read_manifest(dir / "capture.yaml"), fpp::parse_manifest(kValid, kOrigin));
    expect_input_error([&] { fpp::read_manifest(dir / "none.yaml"); }, dir / "none.yaml", "");
}

// ---------------------------------------------------------------------------
// Rejections of frame files (read_capture_set)
// ---------------------------------------------------------------------------

TEST(CaptureSetRejects, MissingFrameFile) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    fs::remove(folder / "f3.png");
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / "f3.png", "frames[3]",
                       "not found");
}

// A name the file system cannot look up (longer than NAME_MAX) is the
// reader's InputError naming the field, not a std::filesystem error (found
// by fuzzing the reader).
TEST(CaptureSetRejects, FrameNameTheFileSystemCannotLookUp) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    const std::string name = std::string(300, 'a') + ".png";
    std::string text = fpp::yaml_fields::read_text_file(folder / "capture.yaml");
    const auto at = text.find("f3.png");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, 6, name);
    write_text(folder / "capture.yaml", text);
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / name, "frames[3]",
                       "cannot be looked up");
}

TEST(CaptureSet, ReadsOnlyTheFramesOfTheKeptBlocks) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    const auto all = fpp::read_capture_set(folder);
    // The gray block's frames (f4..f7) are neither checked nor read.
    fs::remove(folder / "f5.png");
    const auto not_gray = [](const fpp::PatternBlock& b) {
        return !std::holds_alternative<fpp::GrayBlock>(b);
    };
    const auto some = fpp::read_capture_set(folder, not_gray);
    ASSERT_EQ(some.manifest.sequence.size(), 2u);
    EXPECT_TRUE(std::holds_alternative<fpp::WhiteBlock>(some.manifest.sequence[0]));
    EXPECT_TRUE(std::holds_alternative<fpp::PhaseBlock>(some.manifest.sequence[1]));
    EXPECT_EQ(some.manifest.frames,
              (std::vector<std::string>{"f0.png", "f1.png", "f2.png", "f3.png"}));
    expect_same_frames(some.frames,
                       std::vector<fpp::Frame>(all.frames.begin(), all.frames.begin() + 4));
    // A kept frame's error names its place in capture.yaml.
    const auto not_phase = [](const fpp::PatternBlock& b) {
        return !std::holds_alternative<fpp::PhaseBlock>(b);
    };
    expect_input_error([&] { fpp::read_capture_set(folder, not_phase); }, folder / "f5.png",
                       "frames[5]", "not found");
}

TEST(CaptureSetRejects, FrameOfTheWrongSize) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    fpp::write_png(folder / "f2.png", random_frame({16, 13}, 8, 9));
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / "f2.png", "frames[2]",
                       "16x13");
}

TEST(CaptureSetRejects, FramesOfMixedBitDepth) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    fpp::write_png(folder / "f1.png", random_frame({16, 12}, 16, 9));
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / "f1.png", "frames[1]",
                       "16-bit but frames[0] is 8-bit");
}

TEST(CaptureSetRejects, ColourFrame) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    fpp::write_png(folder / "f0.png", fpp::Image<std::uint8_t>(16, 12, 3));
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / "f0.png", "frames[0]",
                       "single-channel");
}

TEST(CaptureSetRejects, CorruptFrame) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    fs::resize_file(folder / "f4.png", fs::file_size(folder / "f4.png") / 2);
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / "f4.png", "frames[4]");
}

TEST(CaptureSetRejects, TruthFileListedButMissing) {
    TempDir dir;
    const fs::path folder = make_set(dir);
    write_text(folder / "capture.yaml",
               with("metadata:", "truth:\n  xyz: truth_xyz.tiff\nmetadata:"));
    expect_input_error([&] { fpp::read_capture_set(folder); }, folder / "truth_xyz.tiff",
                       "truth.xyz", "not found");
}

TEST(CaptureSetRejects, MissingManifest) {
    TempDir dir;
    expect_input_error([&] { fpp::read_capture_set(dir.path()); }, dir / "capture.yaml", "");
}

// ---------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------

TEST(CaptureSetWrite, ExactLayout) {
    fpp::CaptureManifest m;
    m.camera = {1600, 1200};
    m.projector = {1280, 800};
    fpp::PhaseBlock p;
    p.axis = fpp::Axis::x;
    p.period = 20.0;
    p.steps = 3;
    p.shift_sign = -1;
    p.phase_offset = -3.141592653589793;
    fpp::CenterlineBlock c;
    c.axis = fpp::Axis::y;
    c.position = 399.5;
    c.width = 2.0;
    m.sequence = {fpp::WhiteBlock{}, p, c};
    m.frames = {"000.png", "001.png", "002.png", "003.png", "004.png"};
    m.truth = fpp::TruthFiles{"truth_xyz.tiff", "truth_proj.tiff"};
    m.metadata_yaml = "exposure_us: 8000";
    const std::string expected = R"(format: fpp-capture/1
camera:    {width: 1600, height: 1200}
projector: {width: 1280, height: 800}
frames: [000.png, 001.png, 002.png, 003.png, 004.png]
sequence:
  - pattern: white
  - pattern: phase
    axis: x
    period: 20.0
    steps: 3
    shift_sign: -1
    phase_offset: -3.141592653589793
  - pattern: centerline
    axis: y
    position: 399.5
    width: 2.0
truth:
  xyz: truth_xyz.tiff
  projector: truth_proj.tiff
metadata:
  exposure_us: 8000
)";
    EXPECT_EQ(fpp::manifest_to_yaml(m), expected);
    EXPECT_EQ(fpp::parse_manifest(expected, kOrigin), m);
}

TEST(CaptureSetWrite, GrayBlockWritesEveryFieldAndEmptyMetadata) {
    auto m = fpp::parse_manifest(kValid, kOrigin);
    m.metadata_yaml.clear();
    const std::string yaml = fpp::manifest_to_yaml(m);
    EXPECT_NE(yaml.find("  - pattern: gray\n    axis: x\n    period: 8.0\n    bits: 3\n"
                        "    complementary: true\n    inverse: false\n"),
              std::string::npos)
        << yaml;
    EXPECT_NE(yaml.find("    shift_sign: 1\n    phase_offset: 0.0\n"), std::string::npos) << yaml;
    EXPECT_EQ(yaml.substr(yaml.size() - 13), "metadata: {}\n");
    EXPECT_EQ(fpp::parse_manifest(yaml, kOrigin), m);
}

TEST(CaptureSetWrite, RoundTrip8And16Bit) {
    for (const int depth : {8, 16}) {
        SCOPED_TRACE(depth);
        TempDir dir;
        const auto m = fpp::parse_manifest(kValid, kOrigin);
        const auto frames = frames_for(m, depth);
        fpp::write_capture_set(dir / "set", m, frames);
        EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"set"}); // no temporary left
        const fpp::CaptureSet set = fpp::read_capture_set(dir / "set");
        EXPECT_EQ(set.folder, dir / "set");
        EXPECT_EQ(set.manifest, m);
        expect_same_frames(set.frames, frames);
        EXPECT_EQ(listing(dir / "set").size(), 9u); // 8 frames + capture.yaml
    }
}

TEST(CaptureSetWrite, RoundTripKeepsNumbersNamesAndMetadataExactly) {
    TempDir dir;
    auto m = fpp::parse_manifest(kValid, kOrigin);
    auto& p = std::get<fpp::PhaseBlock>(m.sequence[1]);
    p.period = 8.0;
    p.phase_offset = 0.1 + 0.2; // not a short decimal
    p.shift_sign = -1;
    m.frames = {"frames/a b.png", "007",     "true",   "f#3.png",
                "x:y.png",        "-f5.png", "f6.png", "ü.png"};
    m.metadata_yaml = "exposure_us: 8000\nlens:\n  focal_mm: 12.5\n  name: \"C-mount: 1/1.8\"\n"
                      "notes: [a, b]";
    fpp::write_capture_set(dir / "set", m, frames_for(m));
    const auto back = fpp::read_capture_set(dir / "set");
    EXPECT_EQ(std::get<fpp::PhaseBlock>(back.manifest.sequence[1]).phase_offset, 0.1 + 0.2);
    EXPECT_EQ(back.manifest.frames, m.frames);
    // The metadata map is the same (compare through a second round trip, whose
    // text must then be stable).
    EXPECT_EQ(YAML::Dump(YAML::Load(back.manifest.metadata_yaml)),
              YAML::Dump(YAML::Load(m.metadata_yaml)));
    fpp::write_capture_set(dir / "again", back.manifest, back.frames);
    EXPECT_EQ(fpp::read_manifest(dir / "again" / "capture.yaml"), back.manifest);
}

TEST(CaptureSetWrite, TruthImagesAreWrittenAndRead) {
    TempDir dir;
    auto m = fpp::parse_manifest(kValid, kOrigin);
    m.truth = fpp::TruthFiles{"truth_xyz.tiff", "truth_proj.tiff"};
    fpp::Image<float> xyz(m.camera, 3, 500.25f);
    xyz.at(3, 4, 2) = std::nanf("");
    fpp::Image<float> proj(m.camera, 2, 17.5f);
    fpp::write_capture_set(dir / "set", m, frames_for(m), {&xyz, &proj});
    const auto set = fpp::read_capture_set(dir / "set");
    ASSERT_TRUE(set.manifest.truth.has_value());
    EXPECT_EQ(set.manifest.truth->xyz, "truth_xyz.tiff");
    const auto xyz_back = fpp::read_tiff_float(dir / "set" / "truth_xyz.tiff");
    EXPECT_EQ(xyz_back.at(0, 0, 2), 500.25f);
    EXPECT_TRUE(std::isnan(xyz_back.at(3, 4, 2)));
    EXPECT_EQ(fpp::read_tiff_float(dir / "set" / "truth_proj.tiff").channels(), 2);

    // Listed but not given, or given with the wrong channel count: refused, nothing written.
    expect_input_error(
        [&] {
            fpp::write_capture_set(dir / "b", m, frames_for(m), {&xyz, nullptr});
        },
        dir / "b" / "capture.yaml", "truth.projector", "no image");
    expect_input_error(
        [&] {
            fpp::write_capture_set(dir / "c", m, frames_for(m), {&proj, &proj});
        },
        dir / "c" / "capture.yaml", "truth.xyz", "3-channel");
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"set"});
}

TEST(CaptureSetWrite, ExistingTargetIsRefusedAndUntouched) {
    TempDir dir;
    fs::create_directory(dir / "set");
    write_text(dir / "set" / "keep.txt", "x");
    const auto m = fpp::parse_manifest(kValid, kOrigin);
    EXPECT_THROW(fpp::write_capture_set(dir / "set", m, frames_for(m)), fpp::IoError);
    EXPECT_EQ(listing(dir / "set"), std::vector<std::string>{"keep.txt"});
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"set"});
}

TEST(CaptureSetWrite, InvalidManifestIsRefusedAndNothingIsWritten) {
    TempDir dir;
    auto m = fpp::parse_manifest(kValid, kOrigin);
    std::get<fpp::PhaseBlock>(m.sequence[1]).steps = 2;
    m.frames.pop_back();
    expect_input_error([&] { fpp::write_capture_set(dir / "set", m, frames_for(m)); },
                       dir / "set" / "capture.yaml", "sequence[1].steps");
    EXPECT_TRUE(listing(dir.path()).empty());

    auto n = fpp::parse_manifest(kValid, kOrigin);
    n.metadata_yaml = "[not, a, map]";
    expect_input_error([&] { fpp::write_capture_set(dir / "set", n, frames_for(n)); },
                       dir / "set" / "capture.yaml", "metadata");
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(CaptureSetWrite, FramesNotMatchingTheManifestAreRefused) {
    TempDir dir;
    const auto m = fpp::parse_manifest(kValid, kOrigin);
    auto frames = frames_for(m);
    frames.pop_back();
    expect_input_error([&] { fpp::write_capture_set(dir / "set", m, frames); },
                       dir / "set" / "capture.yaml", "frames", "7 frame images");

    frames = frames_for(m);
    frames[5] = random_frame({15, 12}, 8, 1);
    expect_input_error([&] { fpp::write_capture_set(dir / "set", m, frames); },
                       dir / "set" / "f5.png", "frames[5]", "15x12");

    frames = frames_for(m);
    frames[6] = random_frame({16, 12}, 16, 1);
    expect_input_error([&] { fpp::write_capture_set(dir / "set", m, frames); },
                       dir / "set" / "f6.png", "frames[6]", "16-bit");
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(CaptureSetWrite, FailureDuringTheWriteLeavesNothingBehind) {
    // "a" is both a frame file and, through "a/x.png", a folder: the write
    // fails after other frames are already on disk.
    TempDir dir;
    auto m = fpp::parse_manifest(kValid, kOrigin);
    m.frames[0] = "a/x.png";
    m.frames[7] = "a";
    EXPECT_THROW(fpp::write_capture_set(dir / "set", m, frames_for(m)), fpp::IoError);
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(CaptureSetWrite, MissingParentFolderIsIoError) {
    TempDir dir;
    const auto m = fpp::parse_manifest(kValid, kOrigin);
    EXPECT_THROW(fpp::write_capture_set(dir / "no" / "set", m, frames_for(m)), fpp::IoError);
    EXPECT_TRUE(listing(dir.path()).empty());
}

// ---------------------------------------------------------------------------
// Sequences alone and boards
// ---------------------------------------------------------------------------

TEST(SequenceFile, ParsesSequenceAndIgnoresOtherKeys) {
    const std::string text = R"(name: my-scan
exposure_us: 4000
sequence:
  - {pattern: white}
  - {pattern: phase, axis: y, period: 18.5, steps: 4, shift_sign: -1}
  - {pattern: gray, axis: y, period: 18.5, bits: 7, inverse: true}
)";
    const auto seq = fpp::parse_sequence(text, "scan.yaml");
    ASSERT_EQ(seq.size(), 3u);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(seq[1]).period, 18.5);
    EXPECT_TRUE(std::get<fpp::GrayBlock>(seq[2]).inverse);
    TempDir dir;
    write_text(dir / "scan.yaml", text);
    EXPECT_EQ(fpp::read_sequence(dir / "scan.yaml"), seq);
}

TEST(SequenceFile, RejectionsNameTheFileAndField) {
    expect_input_error([] { fpp::parse_sequence("name: x\n", "scan.yaml"); }, "scan.yaml",
                       "sequence", "missing");
    expect_input_error(
        [] {
            fpp::parse_sequence(
                "sequence:\n  - {pattern: phase, axis: x, period: 20, steps: 8, foo: 1}\n",
                "scan.yaml");
        },
        "scan.yaml", "sequence[0].foo", "unknown key");
    expect_input_error(
        [] {
            fpp::parse_sequence("sequence:\n  - {pattern: gray, axis: x, period: 20, bits: 6}\n",
                                "scan.yaml");
        },
        "scan.yaml", "sequence[0].period", "no phase block");
}

TEST(SequenceValidation, ChecksAgainstTheProjector) {
    fpp::PhaseBlock p;
    p.period = 20.0;
    p.steps = 8;
    fpp::GrayBlock g;
    g.period = 20.0;
    g.bits = 5;
    const fpp::Sequence seq = {p, g};
    EXPECT_NO_THROW(fpp::validate_sequence(seq, {640, 480}, "scan.yaml")); // 32 periods
    expect_input_error(
        [&] {
            fpp::validate_sequence(seq, {641, 480}, "scan.yaml");
        },
        "scan.yaml", "sequence[1].bits", "at least 6 bits");
}

TEST(Board, ReadsCheckerboardAndPlane) {
    const auto b = fpp::parse_board(
        "format: fpp-board/1\nkind: checkerboard\ninner_corners: [13, 9]\nsquare_size: 8.0\n",
        "board.yaml");
    EXPECT_EQ(b.kind, fpp::BoardDescription::Kind::checkerboard);
    EXPECT_EQ(b.inner_columns, 13);
    EXPECT_EQ(b.inner_rows, 9);
    EXPECT_EQ(b.square_size, 8.0);
    const auto plane = fpp::parse_board("format: fpp-board/1\nkind: plane\n", "board.yaml");
    EXPECT_EQ(plane.kind, fpp::BoardDescription::Kind::plane);
    TempDir dir;
    write_text(dir / "board.yaml", "format: fpp-board/1\nkind: plane\nsquare_size: 5\n");
    EXPECT_EQ(fpp::read_board(dir / "board.yaml").square_size, 5.0);
}

TEST(Board, Rejections) {
    const std::string ok =
        "format: fpp-board/1\nkind: checkerboard\ninner_corners: [13, 9]\nsquare_size: 8.0\n";
    auto rejected = [](const std::string& text, const std::string& field, const std::string& hint) {
        expect_input_error([&] { fpp::parse_board(text, "/cal/board.yaml"); }, "/cal/board.yaml",
                           field, hint);
    };
    auto replace = [&](const std::string& from, const std::string& to) {
        std::string t = ok;
        return t.replace(t.find(from), from.size(), to);
    };
    rejected(replace("fpp-board/1", "fpp-board/9"), "format", "unknown format");
    rejected(replace("checkerboard", "circles"), "kind", "unknown board kind");
    rejected(replace("[13, 9]", "[13, 9, 1]"), "inner_corners", "[columns, rows]");
    rejected(replace("[13, 9]", "[13, 1]"), "inner_corners[1]", "at least 2");
    rejected(replace("[13, 9]", "[13.5, 9]"), "inner_corners[0]", "integer");
    rejected(replace("inner_corners: [13, 9]\n", ""), "inner_corners", "missing");
    rejected(replace("8.0", "0"), "square_size", "> 0");
    rejected(replace("8.0", ".nan"), "square_size", "non-finite");
    rejected(replace("square_size: 8.0\n", ""), "square_size", "missing");
    rejected(ok + "colour: black\n", "colour", "unknown key");
    rejected("format: fpp-board/1\nkind: plane\ninner_corners: [3, 3]\n", "inner_corners",
             "only for kind checkerboard");
}

// ---------------------------------------------------------------------------
// The real capture sets
// ---------------------------------------------------------------------------

TEST(RealDatasets, EveryCaptureYamlReadsWithItsFrames) {
    const fs::path root = fpp::test::dataset("");
    FPP_REQUIRE_DATASET(root / "slstudio");
    int sets = 0;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        if (entry.path().filename() != "capture.yaml")
            continue;
        SCOPED_TRACE(entry.path().string());
        const fpp::CaptureSet set = fpp::read_capture_set(entry.path().parent_path());
        ++sets;
        EXPECT_EQ(set.frames.size(), set.manifest.frames.size());
        EXPECT_EQ(static_cast<int>(set.frames.size()), fpp::frame_count(set.manifest.sequence));
        for (const auto& f : set.frames) {
            EXPECT_EQ(f.size(), set.manifest.camera);
            EXPECT_EQ(f.bit_depth, 8);
        }
        // The manifest survives our writer unchanged.
        EXPECT_EQ(fpp::parse_manifest(fpp::manifest_to_yaml(set.manifest), entry.path()),
                  set.manifest);
    }
    EXPECT_GE(sets, 9); // six calibration poses, two skull scans, one SLMaster scan

    const auto slmaster = fpp::read_manifest(root / "slmaster" / "monocular" / "capture.yaml");
    EXPECT_EQ(slmaster.camera, (fpp::Size{1280, 1024}));
    EXPECT_EQ(slmaster.projector, (fpp::Size{1920, 1080}));
    const auto& g = std::get<fpp::GrayBlock>(slmaster.sequence[1]);
    EXPECT_EQ(g.bits, 5);
    EXPECT_TRUE(g.complementary);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(slmaster.sequence[0]).phase_offset, -3.141592653589793);

    const auto board = fpp::read_board(root / "slstudio" / "calibration" / "board.yaml");
    EXPECT_EQ(board.inner_columns, 13);
    EXPECT_EQ(board.inner_rows, 9);
    EXPECT_EQ(board.square_size, 10.0);
}
