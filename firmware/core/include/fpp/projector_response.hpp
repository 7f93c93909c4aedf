#pragma once
// The projector's response as the camera sees it: how much light each 8-bit
// drive level emits, measured from a ramp of uniform grey levels shown on a
// flat board (any pose), so that patterns can be rendered through its inverse
// (GammaLut::from_response in fpp/patterns.hpp) and 3- and 4-step phase
// sequences decode as on a linear projector.
//
// Two files (formats in firmware/core/formats/):
//   response-ramp.md        the ramp as captured: a folder with ramp.yaml
//                           (fpp-response-ramp/1) and one PNG per level;
//   projector-response.md   the fitted response (fpp-projector-response/1).
//
// Units: drive levels are the projector's 8-bit input (0 = off, 255 = full
// on); emitted light is relative, with the light of level 0 (black level,
// ambient) removed and the light of level 255 set to 1. Camera samples are DN
// at the frame's container depth (255 for 8-bit frames, 65535 for 16-bit).

#include "fpp/image.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fpp {

inline constexpr const char* kResponseRampFormat = "fpp-response-ramp/1";
inline constexpr const char* kProjectorResponseFormat = "fpp-projector-response/1";
// The ramp of a calibration session is its sub-folder of this name.
inline constexpr const char* kSessionResponseFolder = "response";

// One camera frame per uniform drive level shown full-screen.
struct ResponseRamp {
    std::vector<int> levels;   // drive levels, strictly increasing, 0 first, 255 last, >= 3
    std::vector<Frame> frames; // same order as levels; one size, one bit depth
    // The free-form `metadata` map as YAML text ("" when none), kept as read.
    std::string metadata_yaml;
    // Where it was read from ("" when made in memory): errors name its ramp.yaml.
    std::filesystem::path folder;
};

// 0, 16, 32, ..., 240, 255: 17 levels.
std::vector<int> standard_ramp_levels();
// The projector image of one ramp level: every pixel at `level` (0..255).
// Throws std::invalid_argument for a level or size out of range.
Image<std::uint8_t> ramp_pattern(int level, Size projector);

// Writes `folder`/ramp.yaml and one PNG per level (level-000.png, ...),
// published atomically: `folder` must not exist (IoError) and appears
// complete or not at all. An inconsistent ramp throws InputError naming
// `folder`/ramp.yaml and the field before anything is written.
void write_response_ramp(const std::filesystem::path& folder, const ResponseRamp& ramp);
// Reads a ramp folder strictly: InputError naming the file (ramp.yaml or a
// frame) and the field for an unknown format or key, levels that are not
// integers in 0..255, not strictly increasing, missing 0 or 255 or fewer
// than 3, a frame count that differs from the level count, a frame that is
// missing, not an 8- or 16-bit grey PNG, or of another size or depth than
// frames[0], and frame paths that are absolute, hold "..", or repeat.
ResponseRamp read_response_ramp(const std::filesystem::path& folder);
// Every check the reader makes on the levels and the frames in memory;
// errors name `origin` (a ramp.yaml).
void validate_response_ramp(const ResponseRamp& ramp, const std::filesystem::path& origin);

// Relative emitted light per drive level, sampled: emitted(0) = 0,
// emitted(255) = 1, non-decreasing; monotone cubic interpolation between
// the samples (Fritsch and Carlson, SIAM J. Numer. Anal. 17(2), 1980).
struct ProjectorResponse {
    std::vector<double> levels;  // drive levels, strictly increasing, 0 first, 255 last
    std::vector<double> emitted; // relative light at each level, 0 first, 1 last
    std::size_t pixels_used = 0; // camera pixels the fit averaged (0: not fitted here)
    std::string ramp;            // the ramp it was fitted from ("" when unknown)

    // Relative emitted light at drive level `level` (clamped to 0..255).
    // Throws InputError (see validate) for an invalid response.
    double at(double level) const;
    // Throws InputError(origin, field, ...) for lengths that differ or are
    // below 2, levels not strictly increasing from 0 to 255, emitted light
    // not non-decreasing from 0 to 1, non-finite values.
    void validate(const std::filesystem::path& origin = "projector response") const;
};

// Options of the fit; validate() throws std::invalid_argument naming the field.
struct ResponseFitOptions {
    // A pixel is lit when I(255) - I(0) reaches this fraction of the frames'
    // full scale (0.08: 20 DN of an 8-bit frame); dark pixels (black squares,
    // off the board) only add noise.
    double min_lit_fraction = 0.08;
    // A sample at or above this fraction of full scale is saturated; a pixel
    // saturated at any level is not used.
    double saturation_fraction = 0.999;
    // Fewer usable (lit, never saturated) pixels than this fraction of the
    // frame refuse the ramp.
    double min_usable_fraction = 0.01;
    // Fraction of the pixels' values dropped at each end before averaging a
    // level (a trimmed mean: robust to glints and edges, unbiased under the
    // camera's quantisation, which a median is not).
    double trim_fraction = 0.2;
    // A level whose light falls below the previous level's by more than this
    // many standard errors of the two means, and by more than
    // min_monotonic_drop, makes the ramp non-monotonic (refused); smaller
    // falls are noise and are pooled (isotonic regression).
    double monotonic_sigmas = 4.0;
    double min_monotonic_drop = 0.002; // relative light (frame-to-frame flicker)

    void validate() const;
};

// Fits the response: per camera pixel (I(l) - I(0)) / (I(255) - I(0)) over
// the usable pixels, a trimmed mean per level, small falls pooled, then 0
// and 1 at the ends. Throws InputError naming the ramp's ramp.yaml and the
// field: "levels[k]" for a response that falls at level k beyond the noise,
// "frames[k]" when from frame k on too few lit pixels stay unsaturated
// ("saturates: lower the exposure"), the last frame when too few pixels are
// lit ("too dark"), and every validate_response_ramp rejection.
ProjectorResponse fit_projector_response(const ResponseRamp& ramp,
                                         const ResponseFitOptions& options = {});

// fpp-projector-response/1 YAML, written atomically. Throws InputError
// naming `path` and the field for an invalid response.
void save_projector_response(const std::filesystem::path& path, const ProjectorResponse& response);
std::string projector_response_to_yaml(const ProjectorResponse& response);
// Strict: InputError naming `path` and the field for an unknown format or
// key, and every ProjectorResponse::validate rejection.
ProjectorResponse load_projector_response(const std::filesystem::path& path);
ProjectorResponse parse_projector_response(const std::string& yaml_text,
                                           const std::filesystem::path& origin);

} // namespace fpp
