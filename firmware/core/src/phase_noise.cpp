#include "fpp/phase_noise.hpp"

#include "fpp/parallel.hpp"

#include "phase_math.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <variant>

namespace fpp {

namespace {

void require(bool ok, const std::string& field, const std::string& message) {
    if (!ok)
        throw std::invalid_argument("CameraNoise." + field + ": " + message);
}

void validate_model(const PhaseNoiseModel& model) {
    model.camera.validate();
    if (model.frame_bit_depth != 8 && model.frame_bit_depth != 16)
        throw std::invalid_argument("PhaseNoiseModel.frame_bit_depth: must be 8 or 16, not " +
                                    std::to_string(model.frame_bit_depth));
    if (model.steps < 3)
        throw std::invalid_argument("PhaseNoiseModel.steps: must be >= 3, not " +
                                    std::to_string(model.steps));
    if (!(model.period > 0 && std::isfinite(model.period)))
        throw std::invalid_argument("PhaseNoiseModel.period: must be finite and > 0");
}

// Frame DN per sensor DN.
double frame_per_sensor_dn(const PhaseNoiseModel& model) {
    return std::ldexp(1.0, model.frame_bit_depth - model.camera.sensor_bit_depth);
}

} // namespace

void CameraNoise::validate() const {
    require(std::isfinite(read_noise_dn) && read_noise_dn >= 0, "read_noise_dn",
            "must be finite and >= 0");
    require(std::isfinite(gain_e_per_dn) && gain_e_per_dn >= 0, "gain_e_per_dn",
            "must be finite and >= 0 (0 = no shot noise term)");
    require(sensor_bit_depth >= 8 && sensor_bit_depth <= 16, "sensor_bit_depth",
            "must be in 8..16, not " + std::to_string(sensor_bit_depth));
}

PhaseNoiseModel phase_noise_model(const Sequence& sequence, Axis axis, const CameraNoise& camera,
                                  int frame_bit_depth) {
    PhaseNoiseModel model;
    model.camera = camera;
    model.frame_bit_depth = frame_bit_depth;
    for (const PatternBlock& block : sequence)
        if (const auto* p = std::get_if<PhaseBlock>(&block))
            if (p->axis == axis && (model.steps == 0 || p->period < model.period)) {
                model.steps = p->steps;
                model.period = p->period;
            }
    if (model.steps == 0)
        throw std::invalid_argument(std::string("phase_noise_model: the sequence has no phase "
                                                "block on axis ") +
                                    to_string(axis));
    validate_model(model);
    return model;
}

double sample_variance_dn2(const PhaseNoiseModel& model, double mean_dn) {
    const double s = frame_per_sensor_dn(model);
    const double q = std::max(1.0, s);
    const double read = s * model.camera.read_noise_dn;
    const double shot = model.camera.gain_e_per_dn > 0
                            ? s * std::max(mean_dn, 0.0) / model.camera.gain_e_per_dn
                            : 0.0;
    return read * read + shot + q * q / 12.0;
}

void coordinate_sigma(const Image<float>& modulation, const Image<float>& mean,
                      const PhaseNoiseModel& model, Image<float>& out) {
    validate_model(model);
    if (modulation.channels() != 1 || mean.channels() != 1 || modulation.size() != mean.size())
        throw std::invalid_argument("coordinate_sigma: modulation and mean must be 1-channel "
                                    "images of the same size");
    const Size size = modulation.size();
    if (out.size() != size || out.channels() != 1)
        out = Image<float>(size, 1);
    if (size.width <= 0 || size.height <= 0)
        return;

    // sigma = k sqrt(sigma_I^2 / B_signal^2), k = sqrt(2 / N) period / (2 pi),
    // sigma_I^2 = v0 + shot_per_dn A, B_signal^2 = the measured B^2 less the
    // noise's share 4 sigma_I^2 / N, kept at or above B^2 / 2.
    const auto v0 = static_cast<float>(sample_variance_dn2(model, 0.0));
    const auto shot_per_dn = static_cast<float>(sample_variance_dn2(model, 1.0)) - v0;
    const auto k = static_cast<float>(std::sqrt(2.0 / model.steps) * model.period /
                                      (2.0 * 3.14159265358979323846));
    const auto noise_share = static_cast<float>(4.0 / model.steps);
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    constexpr float kFloatMax = std::numeric_limits<float>::max();
    ThreadPool& pool = ThreadPool::shared();
    const int grain = std::max(1, size.height / (4 * pool.size()));
    pool.parallel_for(size.height, grain, [&](int y0, int y1, int) {
        for (int y = y0; y < y1; ++y) {
            const float* __restrict b = modulation.row(y);
            const float* __restrict a = mean.row(y);
            float* __restrict o = out.row(y);
            for (int x = 0; x < size.width; ++x) {
                const float av = a[x] < 0.0f ? 0.0f : a[x]; // NaN stays NaN
                const float variance = v0 + shot_per_dn * av;
                const float b2 = b[x] * b[x];
                const float signal2 = std::max(b2 - noise_share * variance, 0.5f * b2);
                const bool usable = b[x] > 0.0f && b[x] <= kFloatMax;
                o[x] = usable ? k * detail::sqrt_fast(variance / signal2) : kNaN;
            }
        }
    });
}

} // namespace fpp
