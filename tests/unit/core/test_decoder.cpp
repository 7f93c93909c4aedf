// The decoder's API contract on synthesised frames
// (tests/support/synthetic_decode.hpp): recycled results and restarted
// decoders give the same bytes, bad frames and options are refused with
// named errors, 16-bit frames decode like 8-bit ones, undecodable sequences
// throw.

#include "synthetic_decode.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace fpp::test::synthetic;

TEST(DecodeApi, RecycledResultGivesTheSameBytes) {
    const Synth s = Synth::standard();
    const CaptureSet set = s.capture(method_sequences()[0].sequence, 8, 1.0);
    const DecodeResult fresh = fpp::decode(set);
    DecodeResult reused = fpp::decode(s.capture(method_sequences()[0].sequence, 8, 3.0, 99));
    const float* memory = reused.proj_x.data();
    fpp::decode(set, reused);
    EXPECT_EQ(reused.proj_x.data(), memory); // no new allocation
    EXPECT_TRUE(same_bytes(fresh.proj_x, reused.proj_x));
    EXPECT_TRUE(same_bytes(fresh.proj_y, reused.proj_y));
    EXPECT_TRUE(same_bytes(fresh.mask, reused.mask));
    EXPECT_TRUE(same_bytes(fresh.modulation, reused.modulation));
    fpp::StreamingDecoder d(set.manifest.sequence, set.manifest.camera, set.manifest.projector, {},
                            std::move(reused));
    for (const auto& f : set.frames)
        d.push(f);
    const DecodeResult streamed = d.finish();
    EXPECT_EQ(streamed.proj_x.data(), memory);
    EXPECT_TRUE(same_bytes(fresh.proj_x, streamed.proj_x));
    EXPECT_TRUE(same_bytes(fresh.mean, streamed.mean));
}

// One decoder restarted scan after scan, as the scanner uses it: every
// sequence gives the batch decoder's bytes after a finished scan of another
// bit depth and after a scan abandoned part-way, and reuses the images handed
// back to it.
TEST(DecodeApi, RestartedDecoderGivesTheSameBytesScanAfterScan) {
    const Synth s = Synth::standard();
    for (const NamedSequence& ns : method_sequences()) {
        const CaptureSet deep = s.capture(ns.sequence, 16, 40.0, 5);
        const CaptureSet shallow = s.capture(ns.sequence, 8, 1.0, 6);
        fpp::StreamingDecoder d(ns.sequence, s.camera, s.projector);
        auto run = [&](const CaptureSet& set) {
            for (const auto& f : set.frames)
                d.push(f);
            return d.finish();
        };
        const DecodeResult first = run(deep);
        EXPECT_TRUE(same_bytes(first.modulation, fpp::decode(deep).modulation)) << ns.name;
        d.restart(DecodeResult(first));
        // Abandoned after a few frames: the next scan starts from its first frame.
        for (std::size_t i = 0; i < 3 && i < shallow.frames.size(); ++i)
            d.push(shallow.frames[i]);
        d.restart();
        DecodeResult second = run(shallow);
        const DecodeResult batch = fpp::decode(shallow);
        EXPECT_TRUE(same_bytes(batch.proj_x, second.proj_x)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.proj_y, second.proj_y)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.modulation, second.modulation)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.mean, second.mean)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.mask, second.mask)) << ns.name;
        const float* reused = second.modulation.data();
        d.restart(std::move(second));
        const DecodeResult third = run(deep);
        EXPECT_EQ(third.modulation.data(), reused) << ns.name; // no new allocation
        EXPECT_TRUE(same_bytes(first.proj_x, third.proj_x)) << ns.name;
        EXPECT_TRUE(same_bytes(first.mask, third.mask)) << ns.name;
    }
}

Sequence small_sequence() {
    return {fpp::WhiteBlock{}, fpp::BlackBlock{}, phase(Axis::x, 20, 4),
            gray(Axis::x, 20, 6, true)};
}

TEST(DecodeApi, PushRejectsBadFrames) {
    const Synth s = Synth::standard();
    const CaptureSet set = s.capture(small_sequence());
    {
        fpp::StreamingDecoder d(set.manifest.sequence, s.camera, s.projector);
        Frame wrong_size;
        wrong_size.u8 = Image<std::uint8_t>(s.camera.width - 1, s.camera.height);
        EXPECT_THROW(d.push(wrong_size), fpp::InputError);
        Frame twelve = set.frames[0];
        twelve.bit_depth = 12;
        EXPECT_THROW(d.push(twelve), fpp::InputError);
        Frame empty;
        EXPECT_THROW(d.push(empty), fpp::InputError);
        Frame two_channels;
        two_channels.u8 = Image<std::uint8_t>(s.camera, 2);
        EXPECT_THROW(d.push(two_channels), fpp::InputError);
        EXPECT_EQ(d.frames_received(), 0);
        d.push(set.frames[0]);
        Frame deep;
        deep.bit_depth = 16;
        deep.u16 = Image<std::uint16_t>(s.camera);
        try {
            d.push(deep);
            ADD_FAILURE() << "accepted a 16-bit frame after an 8-bit one";
        } catch (const fpp::InputError& e) { // no file: the decoder, and the frame's field
            EXPECT_EQ(e.file(), std::filesystem::path(fpp::kDecoderOrigin));
            EXPECT_EQ(e.field(), "frames[1]");
            EXPECT_NE(std::string(e.what()).find("differs from the first frame's 8"),
                      std::string::npos)
                << e.what();
        }
        EXPECT_EQ(d.frames_received(), 1);
        EXPECT_EQ(d.frames_expected(), static_cast<int>(set.frames.size()));
        EXPECT_THROW(d.finish(), std::logic_error);
    }
    {
        fpp::StreamingDecoder d(set.manifest.sequence, s.camera, s.projector);
        for (const auto& f : set.frames)
            d.push(f);
        EXPECT_THROW(d.push(set.frames[0]), fpp::InputError);
        const DecodeResult r = d.finish();
        EXPECT_FALSE(r.proj_x.empty());
        EXPECT_THROW(d.finish(), std::logic_error);
        EXPECT_THROW(d.push(set.frames[0]), std::logic_error);
    }
    {
        CaptureSet missing = set;
        missing.frames.pop_back();
        EXPECT_THROW(fpp::decode(missing), fpp::InputError);
        CaptureSet mixed = set;
        mixed.frames[3] = Frame{16, {}, Image<std::uint16_t>(s.camera)};
        mixed.folder = "scans/plane";
        try {
            (void)fpp::decode(mixed);
            ADD_FAILURE() << "accepted frames of mixed bit depths";
        } catch (const fpp::InputError& e) { // the capture's manifest, and the frame
            EXPECT_EQ(e.file(), std::filesystem::path("scans/plane/capture.yaml"));
            EXPECT_EQ(e.field(), "frames[3]");
        }
    }
}

TEST(DecodeApi, SixteenBitFramesDecodeLikeEightBit) {
    const Synth s = Synth::standard();
    const CaptureSet set = s.capture(method_sequences()[0].sequence, 16);
    const DecodeResult r = fpp::decode(set);
    const Accuracy a = accuracy(r.proj_x, s.truth_x, 20);
    EXPECT_EQ(a.unwrap_errors, 0u);
    EXPECT_LT(a.rms, 0.03);
    EXPECT_GT(a.coverage(), 0.995);
    EXPECT_TRUE(same_bytes(r.proj_x, stream(set).proj_x));
}

TEST(DecodeApi, OptionsValidation) {
    EXPECT_NO_THROW(DecodeOptions{}.validate());
    auto bad = [](auto mutate) {
        DecodeOptions o;
        mutate(o);
        EXPECT_THROW(o.validate(), fpp::InputError);
    };
    bad([](DecodeOptions& o) { o.min_modulation = -0.01; });
    bad([](DecodeOptions& o) { o.min_modulation = 1.0; });
    bad([](DecodeOptions& o) { o.min_modulation = std::nan(""); });
    bad([](DecodeOptions& o) { o.saturation = 0.0; });
    bad([](DecodeOptions& o) { o.saturation = 1.01; });
    bad([](DecodeOptions& o) { o.max_unwrap_disagreement = 0.0; });
    bad([](DecodeOptions& o) { o.max_unwrap_disagreement = 0.51; });
    bad([](DecodeOptions& o) {
        o.max_unwrap_disagreement = std::numeric_limits<double>::infinity();
    });
    bad([](DecodeOptions& o) { o.threads = -1; });
    try {
        DecodeOptions o;
        o.saturation = 2.0;
        o.validate();
        FAIL() << "no exception";
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("saturation"), std::string::npos);
        EXPECT_EQ(e.file(), std::filesystem::path(fpp::kDecodeOptionsOrigin));
        EXPECT_EQ(e.field(), "saturation");
    }
    {
        DecodeOptions o; // phase_error's own check, as the decoder's InputError
        o.phase_error.harmonics = 0;
        EXPECT_THROW(o.validate(), fpp::InputError);
    }
    DecodeOptions o;
    o.threads = -3;
    const Synth s = Synth::standard();
    EXPECT_THROW(fpp::StreamingDecoder(small_sequence(), s.camera, s.projector, o),
                 fpp::InputError);
    EXPECT_THROW(fpp::decode(s.capture(small_sequence()), o), fpp::InputError);
}

TEST(DecodeApi, UndecodableSequencesThrow) {
    const Size cam{40, 30}, proj{800, 600};
    auto rejects = [&](const Sequence& seq, const std::string& fragment) {
        try {
            fpp::StreamingDecoder d(seq, cam, proj);
            ADD_FAILURE() << "accepted a sequence that should fail with: " << fragment;
        } catch (const fpp::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
            EXPECT_EQ(e.file(), std::filesystem::path(fpp::kDecoderOrigin));
        }
    };
    rejects({fpp::WhiteBlock{}, fpp::BlackBlock{}}, "no phase block");
    rejects({}, "no phase block");
    rejects({phase(Axis::x, 20, 8)}, "shorter than the projector extent");
    rejects({phase(Axis::x, 20, 8), gray(Axis::x, 25, 6, true)}, "no phase block on that axis");
    rejects({phase(Axis::x, 20, 8), gray(Axis::x, 20, 4, true)}, "fewer than the projector extent");
    rejects({phase(Axis::x, 20, 8), phase(Axis::x, 22, 8)}, "heterodyne");
    rejects({phase(Axis::x, 20, 8), phase(Axis::x, 20, 4)}, "same period");
    // A gray block alone codes its axis (fpp-capture/2) but needs a threshold.
    rejects({gray(Axis::y, 20, 5, true), phase(Axis::x, 800, 8)},
            "code-only axis needs inverse frames or white and black frames");
    rejects({phase(Axis::x, 20, 2), gray(Axis::x, 20, 6, true)}, "steps");
    // One axis decodable, the other not: still rejected (the user asked for y).
    rejects({phase(Axis::x, 800, 8), phase(Axis::y, 20, 8)}, "axis y");
}

} // namespace
