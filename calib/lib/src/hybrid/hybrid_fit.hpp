#pragma once
// Internal to the hybrid calibration: the parts its two procedures (plane
// and checkerboard sessions) share.

#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/session_folder.hpp"

#include <vector>

namespace fpp::calib::detail {

// Fits every model to the poses' samples: one result per model, each a copy
// of `common` (poses, counts, times) with its table and maps. `model` is the
// stereo model's sample source (checkerboard sessions; empty otherwise).
std::vector<HybridResult>
fit_hybrid_models(const HybridResult& common, const std::vector<PoseSamples>& samples,
                  const Image<float>& rays, Size projector, std::uint64_t calibration_hash,
                  const HybridOptions& options, const std::vector<TableModel>& models,
                  const ModelSampleSource& model);

// The checkerboard (camera-anchored) procedure, for calibrate_hybrid: from
// the poses' views when given (one per pose), else reading every pose.
std::vector<HybridResult> calibrate_hybrid_checkerboard(const SessionFolder& folder,
                                                        const StereoCalibration& calibration,
                                                        std::uint64_t calibration_hash,
                                                        const HybridOptions& options,
                                                        const std::vector<TableModel>& models,
                                                        const std::vector<BoardView>* views);

} // namespace fpp::calib::detail
