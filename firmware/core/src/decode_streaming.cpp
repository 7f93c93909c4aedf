// Public decoder API: options, the streaming decoder and the batch decode().

#include "decode_engine.hpp"
#include "decode_plan.hpp"
#include "fpp/decoder.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace fpp {

void DecodeOptions::validate() const {
    auto reject = [](const char* field, const std::string& rule, double value) {
        throw std::invalid_argument(std::string("DecodeOptions::") + field + " must be " + rule +
                                    ", got " + std::to_string(value));
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
}

struct StreamingDecoder::Impl {
    detail::DecodeEngine engine;
    Impl(const Sequence& sequence, Size camera, Size projector, const DecodeOptions& options,
         DecodeResult* recycled)
        : engine(detail::make_plan(sequence, camera, projector), options,
                 detail::DecodeEngine::Mode::streaming, recycled) {}
};

namespace {
const DecodeOptions& validated(const DecodeOptions& options) {
    options.validate();
    return options;
}
} // namespace

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
    return impl_->engine.finish();
}

DecodeResult decode(const CaptureSet& capture, const DecodeOptions& options) {
    options.validate();
    detail::DecodeEngine engine(detail::make_plan(capture.manifest.sequence,
                                                  capture.manifest.camera,
                                                  capture.manifest.projector),
                                options, detail::DecodeEngine::Mode::batch);
    return engine.run_batch(capture.frames);
}

void decode(const CaptureSet& capture, DecodeResult& result, const DecodeOptions& options) {
    options.validate();
    detail::DecodeEngine engine(detail::make_plan(capture.manifest.sequence,
                                                  capture.manifest.camera,
                                                  capture.manifest.projector),
                                options, detail::DecodeEngine::Mode::batch, &result);
    result = engine.run_batch(capture.frames);
}

} // namespace fpp
