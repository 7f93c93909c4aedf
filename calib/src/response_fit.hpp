#pragma once
// The projector response from a ramp (fpp/projector_response.hpp), shared by
// `response` and `calibrate`: where a session keeps its ramp, and the fit
// with its report.

#include "fpp/projector_response.hpp"

#include <filesystem>
#include <optional>
#include <ostream>

namespace fpp::calib {

// The ramp folder `path` names: `path` itself when it holds ramp.yaml, its
// response/ when that does (a session), else nothing.
std::optional<std::filesystem::path> find_response_ramp(const std::filesystem::path& path);

// Reads and fits the ramp in `ramp_folder`, then writes to `out` the fitted
// light per level and the pixels used; for a simulated ramp (metadata
// projector_gamma) also the error against the rig's true response,
// ((level/255)^gamma). Throws InputError naming the ramp's file and field.
ProjectorResponse fit_and_report_response(const std::filesystem::path& ramp_folder,
                                          std::ostream& out);

// The default file name of a fitted response, beside a calibration's outputs.
inline constexpr const char* kProjectorResponseFile = "projector-response.yaml";

} // namespace fpp::calib
