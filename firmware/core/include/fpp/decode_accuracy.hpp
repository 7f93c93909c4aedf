#pragma once
// Decoded projector coordinates against ground truth (simulated captures).

#include "fpp/image.hpp"

#include <cstddef>

namespace fpp {

struct AxisAccuracy {
    std::size_t truth_valid = 0;   // pixels whose truth is finite
    std::size_t decoded_valid = 0; // pixels decoded (finite), whatever the truth
    std::size_t compared = 0;      // both finite
    std::size_t false_valid = 0;   // decoded where the truth has no projector light
    std::size_t unwrap_errors = 0; // compared pixels with |error| > period / 2
    double rms_px = 0;             // over compared pixels without unwrap errors
    double mean_abs_px = 0;
    double p99_abs_px = 0;
    double max_abs_px = 0;    // over compared pixels without unwrap errors
    double coverage() const { // share of truth-valid pixels decoded
        return truth_valid ? double(compared) / double(truth_valid) : 0.0;
    }
    double unwrap_error_rate() const {
        return compared ? double(unwrap_errors) / double(compared) : 0.0;
    }
};

// `truth` is the 2-channel projector truth image; `channel` 0 = x, 1 = y.
// `period` is the finest fringe period on that axis (projector pixels).
// Throws InputError("compare_to_truth", "truth" or "channel", ...) when the
// images' sizes differ, `decoded` is not 1-channel or `truth` has no `channel`.
AxisAccuracy compare_to_truth(const Image<float>& decoded, const Image<float>& truth, int channel,
                              double period);

} // namespace fpp
