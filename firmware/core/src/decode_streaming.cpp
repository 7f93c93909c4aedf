// Public decoder API: options, the streaming decoder and the batch decode().

#include "decode_engine.hpp"
#include "decode_plan.hpp"
#include "fpp/decoder.hpp"
#include "fpp/error.hpp"
#include "fpp/parallel.hpp"

#include <cmath>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace fpp {

void DecodeOptions::validate() const {
    auto reject = [](const char* field, const std::string& rule, double value) {
        throw InputError(kDecodeOptionsOrigin, field,
                         "must be " + rule + ", got " + std::to_string(value));
    };
    if (!(std::isfinite(min_modulation) && min_modulation >= 0 && min_modulation < 1))
        reject("min_modulation", "in [0, 1)", min_modulation);
    if (!(std::isfinite(saturation) && saturation > 0 && saturation <= 1))
        reject("saturation", "in (0, 1]", saturation);
    if (!(std::isfinite(max_unwrap_disagreement) && max_unwrap_disagreement > 0 &&
          max_unwrap_disagreement <= 0.5))
        reject("max_unwrap_disagreement", "in (0, 0.5]", max_unwrap_disagreement);
    if (threads < 0 || threads > 1024)
        reject("threads", "in [0, 1024]", threads);
    try {
        phase_error.validate();
    } catch (const std::invalid_argument& e) { // "PhaseErrorOptions::<field> must be ..."
        throw InputError(kDecodeOptionsOrigin, "phase_error", e.what());
    }
}

namespace {

// The manifest a capture's errors name: its capture.yaml ("capture.yaml"
// for a set that was never read from a folder).
std::filesystem::path manifest_of(const std::filesystem::path& folder) {
    return folder / "capture.yaml";
}

const DecodeOptions& validated(const DecodeOptions& options) {
    options.validate();
    return options;
}

// What the phase-error correction needs of a plan: each coded axis's finest
// phase block (the one its fine coordinate comes from).
struct FinestBlocks {
    std::optional<PhaseBlock> axis[2];
    explicit FinestBlocks(const detail::Plan& plan) {
        // Code-only and micro axes have no N-step block to correct.
        for (int a = 0; a < 2; ++a)
            if (plan.axes[a].coded && plan.axes[a].report_phase >= 0 &&
                plan.phases[static_cast<std::size_t>(plan.axes[a].report_phase)].kind !=
                    detail::PhaseKind::micro)
                axis[a] = plan.phases[static_cast<std::size_t>(plan.axes[a].report_phase)].block;
    }
};

// The pass over a finished result: corrects each coded axis when asked
// (after unwrapping and validity, which it leaves alone).
void correct_phase_errors(DecodeResult& result, const FinestBlocks& finest,
                          const DecodeOptions& options) {
    result.phase_correction_x = {};
    result.phase_correction_y = {};
    if (!options.correct_phase_error)
        return;
    ThreadPool& pool = ThreadPool::shared(options.threads);
    const PhaseErrorOptions& o = options.phase_error;
    if (finest.axis[0] && !result.proj_x.empty())
        result.phase_correction_x =
            correct_phase_error(result.proj_x, result.mask, *finest.axis[0], o, &pool);
    if (finest.axis[1] && !result.proj_y.empty())
        result.phase_correction_y =
            correct_phase_error(result.proj_y, result.mask, *finest.axis[1], o, &pool);
}

} // namespace

struct StreamingDecoder::Impl {
    DecodeOptions options;
    FinestBlocks finest;
    detail::DecodeEngine engine;
    Impl(detail::Plan plan, const DecodeOptions& o, DecodeResult* recycled)
        : options(o), finest(plan),
          engine(std::move(plan), o, detail::DecodeEngine::Mode::streaming, recycled) {}
    Impl(const Sequence& sequence, Size camera, Size projector, const DecodeOptions& o,
         DecodeResult* recycled)
        : Impl(detail::make_plan(sequence, camera, projector, kDecoderOrigin), o, recycled) {}
};

StreamingDecoder::StreamingDecoder(const Sequence& sequence, Size camera, Size projector,
                                   const DecodeOptions& options)
    : impl_(std::make_unique<Impl>(sequence, camera, projector, validated(options), nullptr)) {}

StreamingDecoder::StreamingDecoder(const Sequence& sequence, Size camera, Size projector,
                                   const DecodeOptions& options, DecodeResult&& recycled)
    : impl_(std::make_unique<Impl>(sequence, camera, projector, validated(options), &recycled)) {}

StreamingDecoder::~StreamingDecoder() = default;
StreamingDecoder::StreamingDecoder(StreamingDecoder&&) noexcept = default;
StreamingDecoder& StreamingDecoder::operator=(StreamingDecoder&&) noexcept = default;

void StreamingDecoder::push(const Frame& frame) {
    push(FrameView(frame));
}

void StreamingDecoder::push(const FrameView& frame) {
    if (!impl_)
        throw std::logic_error("StreamingDecoder: use after move");
    impl_->engine.push(frame);
}

void StreamingDecoder::restart(DecodeResult&& recycled) {
    if (!impl_)
        throw std::logic_error("StreamingDecoder: use after move");
    impl_->engine.restart(&recycled);
}

int StreamingDecoder::frames_received() const {
    return impl_ ? impl_->engine.frames_received() : 0;
}

int StreamingDecoder::frames_expected() const {
    return impl_ ? impl_->engine.frames_expected() : 0;
}

DecodeResult StreamingDecoder::finish() {
    if (!impl_)
        throw std::logic_error("StreamingDecoder: use after move");
    DecodeResult result = impl_->engine.finish();
    correct_phase_errors(result, impl_->finest, impl_->options);
    return result;
}

namespace {

// The batch decode of `frames` described by `manifest` (errors naming
// folder / capture.yaml), into `recycled`'s images when given.
DecodeResult decode_frames(const CaptureManifest& manifest, const std::filesystem::path& folder,
                           std::span<const FrameView> frames, const DecodeOptions& options,
                           DecodeResult* recycled) {
    options.validate();
    detail::Plan plan = detail::make_plan(manifest.sequence, manifest.camera, manifest.projector,
                                          manifest_of(folder));
    const FinestBlocks finest(plan);
    detail::DecodeEngine engine(std::move(plan), options, detail::DecodeEngine::Mode::batch,
                                recycled);
    DecodeResult result = engine.run_batch(frames);
    correct_phase_errors(result, finest, options);
    return result;
}

std::vector<FrameView> views_of(const std::vector<Frame>& frames) {
    return {frames.begin(), frames.end()};
}

} // namespace

DecodeResult decode(const CaptureSet& capture, const DecodeOptions& options) {
    return decode_frames(capture.manifest, capture.folder, views_of(capture.frames), options,
                         nullptr);
}

void decode(const CaptureSet& capture, DecodeResult& result, const DecodeOptions& options) {
    result =
        decode_frames(capture.manifest, capture.folder, views_of(capture.frames), options, &result);
}

DecodeResult decode(const CaptureView& capture, const DecodeOptions& options) {
    return decode_frames(capture.manifest, capture.folder, capture.frames, options, nullptr);
}

} // namespace fpp
