// Named standard sequences: their blocks, and that every one passes the
// capture-set reader's validation and survives a manifest round trip.

#include "fpp/capture_set.hpp"
#include "fpp/patterns.hpp"
#include "fpp/sequences.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace {

fpp::CaptureManifest manifest_for(const fpp::Sequence& sequence, fpp::Size projector) {
    fpp::CaptureManifest m;
    m.camera = {64, 48};
    m.projector = projector;
    m.sequence = sequence;
    for (int i = 0; i < fpp::frame_count(sequence); ++i)
        m.frames.push_back(std::to_string(i) + ".png");
    return m;
}

} // namespace

TEST(Sequences, EveryNamedSequencePassesTheReadersValidationAndRoundTrips) {
    for (const fpp::Size projector :
         {fpp::Size{1280, 800}, fpp::Size{1824, 1140}, fpp::Size{1920, 1080}, fpp::Size{912, 1140},
          fpp::Size{641, 479}}) {
        for (const auto& name : fpp::standard_sequence_names()) {
            SCOPED_TRACE(name + " on " + std::to_string(projector.width) + "x" +
                         std::to_string(projector.height));
            const fpp::Sequence seq = fpp::standard_sequence(name, projector);
            ASSERT_FALSE(seq.empty());
            EXPECT_NO_THROW(fpp::validate_sequence(seq, projector, "test"));
            const auto m = manifest_for(seq, projector);
            const std::string yaml = fpp::manifest_to_yaml(m);
            EXPECT_EQ(fpp::parse_manifest(yaml, "capture.yaml"), m) << yaml;
        }
    }
}

TEST(Sequences, GrayXyLayout) {
    const auto seq = fpp::standard_sequence("gray-xy", {1280, 800});
    ASSERT_EQ(seq.size(), 6u);
    EXPECT_TRUE(std::holds_alternative<fpp::WhiteBlock>(seq[0]));
    EXPECT_TRUE(std::holds_alternative<fpp::BlackBlock>(seq[1]));
    const auto& px = std::get<fpp::PhaseBlock>(seq[2]);
    EXPECT_EQ(px.axis, fpp::Axis::x);
    EXPECT_EQ(px.period, 20.0);
    EXPECT_EQ(px.steps, 8);
    EXPECT_EQ(px.shift_sign, 1);
    const auto& gx = std::get<fpp::GrayBlock>(seq[3]);
    EXPECT_EQ(gx.axis, fpp::Axis::x);
    EXPECT_EQ(gx.period, 20.0);
    EXPECT_EQ(gx.bits, 6); // floor(1279/20) = 63 < 2^6
    EXPECT_TRUE(gx.complementary);
    EXPECT_FALSE(gx.inverse);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(seq[4]).axis, fpp::Axis::y);
    const auto& gy = std::get<fpp::GrayBlock>(seq[5]);
    EXPECT_EQ(gy.axis, fpp::Axis::y);
    EXPECT_EQ(gy.bits, 6); // floor(799/20) = 39
    EXPECT_EQ(fpp::frame_count(seq), 2 + 8 + 7 + 8 + 7);

    // 1920 columns need 7 bits (floor(1919/20) = 95).
    EXPECT_EQ(std::get<fpp::GrayBlock>(fpp::standard_sequence("gray-x", {1920, 1080})[3]).bits, 7);
}

TEST(Sequences, GrayBitsNeeded) {
    EXPECT_EQ(fpp::gray_bits_needed(60.0, 1920), 5); // SLMaster's set: 32 periods exactly
    EXPECT_EQ(fpp::gray_bits_needed(60.0, 1921), 6);
    EXPECT_EQ(fpp::gray_bits_needed(20.0, 20), 1);
    EXPECT_EQ(fpp::gray_bits_needed(20.0, 41), 2);
    EXPECT_EQ(fpp::gray_bits_needed(20.0, 81), 3);
    EXPECT_THROW(fpp::gray_bits_needed(0.0, 100), std::invalid_argument);
}

TEST(Sequences, PlainAndInverseGray) {
    const auto plain = fpp::standard_sequence("plain-gray-x", {1280, 800});
    ASSERT_EQ(plain.size(), 4u);
    EXPECT_FALSE(std::get<fpp::GrayBlock>(plain[3]).complementary);
    EXPECT_FALSE(std::get<fpp::GrayBlock>(plain[3]).inverse);

    const auto inverse = fpp::standard_sequence("inverse-gray-x", {1280, 800});
    ASSERT_EQ(inverse.size(), 2u);
    const auto& g = std::get<fpp::GrayBlock>(inverse[1]);
    EXPECT_TRUE(g.inverse);
    EXPECT_TRUE(g.complementary);
    EXPECT_EQ(fpp::frame_count(inverse), 8 + 2 * 7);
}

TEST(Sequences, MultiPeriodAndHeterodyne) {
    const auto multi = fpp::standard_sequence("multi-period-x", {1280, 800});
    ASSERT_EQ(multi.size(), 3u);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(multi[0]).period, 20.0);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(multi[1]).period, 160.0);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(multi[2]).period, 1280.0);

    const auto het = fpp::standard_sequence("heterodyne-x", {1280, 800});
    ASSERT_EQ(het.size(), 3u);
    EXPECT_DOUBLE_EQ(std::get<fpp::PhaseBlock>(het[0]).period, 20.0);
    EXPECT_DOUBLE_EQ(std::get<fpp::PhaseBlock>(het[1]).period, 1280.0 / 63.0);
    EXPECT_DOUBLE_EQ(std::get<fpp::PhaseBlock>(het[2]).period, 1280.0 / 56.0);
    for (const auto& b : het)
        EXPECT_EQ(std::get<fpp::PhaseBlock>(b).steps, 8);
}

TEST(Sequences, CenterlineXyIsThePapersSequence) {
    const fpp::Size projector{1280, 800};
    const auto seq = fpp::standard_sequence("centerline-xy", projector);
    ASSERT_EQ(seq.size(), 5u);
    EXPECT_TRUE(std::holds_alternative<fpp::WhiteBlock>(seq[0]));
    const auto& cx = std::get<fpp::CenterlineBlock>(seq[2]);
    EXPECT_EQ(cx.axis, fpp::Axis::x);
    EXPECT_EQ(cx.position, 639.5);
    EXPECT_EQ(cx.width, 2.0);
    // Exactly the two middle columns are lit.
    const auto image = fpp::render_pattern(cx, 0, projector);
    for (int x = 0; x < projector.width; ++x) {
        EXPECT_EQ(image.at(x, 100), (x == 639 || x == 640) ? 255 : 0) << x;
    }
    const auto& cy = std::get<fpp::CenterlineBlock>(seq[4]);
    EXPECT_EQ(cy.axis, fpp::Axis::y);
    EXPECT_EQ(cy.position, 399.5);
    EXPECT_EQ(fpp::frame_count(seq), 1 + 8 + 1 + 8 + 1);
}

TEST(Sequences, SlstudioLikeMatchesTheSlstudioDatasetCodec) {
    // The SLStudio example data on its 1824 x 1140 projector: periods 114 and 1824.
    const auto seq = fpp::standard_sequence("slstudio-like-x", {1824, 1140});
    ASSERT_EQ(seq.size(), 2u);
    const auto& fine = std::get<fpp::PhaseBlock>(seq[0]);
    const auto& cue = std::get<fpp::PhaseBlock>(seq[1]);
    EXPECT_EQ(fine.period, 114.0);
    EXPECT_EQ(cue.period, 1824.0);
    EXPECT_EQ(fine.steps, 3);
    EXPECT_EQ(cue.steps, 3);
    EXPECT_EQ(fine.shift_sign, -1);
    EXPECT_EQ(cue.shift_sign, -1);
}

TEST(Sequences, UnknownNameAndBadProjectorThrow) {
    EXPECT_THROW(fpp::standard_sequence("gray-z", {1280, 800}), std::invalid_argument);
    EXPECT_THROW(fpp::standard_sequence("gray-xy", {0, 800}), std::invalid_argument);
}
