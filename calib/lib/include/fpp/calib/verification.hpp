#pragma once
// Verification of a scanner with a certified artefact after VDI/VDE 2634
// part 2 (`fpp-calib verify`): the artefact found in the cloud of each
// position (fpp/calib/artefact_search.hpp) and its figures, camera frame, mm:
//   P_F  probing error form, per sphere: range of the radial residuals of
//        the least-squares sphere (free radius) after the guideline's
//        exclusion of the 0.3 % of points furthest from it (refitted);
//   P_S  probing error size, per sphere: fitted minus certified diameter;
//   SD   sphere-spacing error, per position of a ball bar: distance of the
//        fitted centres minus the certified centre distance;
//   F    flatness, per position of a plate: range of the signed distances
//        to the least-squares plane after the same exclusion.
// Each against its maximum permissible error (MPE) when one is given: a
// figure passes when |figure| <= MPE.
//
// Refusals (InputError naming the capture or the artefact file):
//   - a position where the artefact is not found whole: a sphere missing,
//     more spheres of the certified diameter than the artefact has, a sphere
//     with too little surface (coverage below the minimum), spheres so close
//     in the camera's view that one hides the other;
//   - a certificate the scans contradict by more than a scanner could be
//     off (`max_credible_error_mm`): a length or a diameter that far from
//     the measured one is a wrong certificate (or file), not a scanner to fail.

#include "fpp/calib/artefact.hpp"
#include "fpp/calib/artefact_search.hpp"
#include "fpp/image.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fpp::calib {

struct MaximumPermissibleErrors {
    std::optional<double> spacing_mm;  // SD
    std::optional<double> form_mm;     // P_F
    std::optional<double> size_mm;     // P_S
    std::optional<double> flatness_mm; // F
};

struct VerificationOptions {
    ArtefactSearchOptions search;
    // Of the hemisphere facing the camera (artefact_search.hpp): a whole
    // sphere scores 0.5 to 0.7, one cut in half by the view's edge 0.22 at
    // 42 px across (400 x 300), 0.28 at 800 x 600, 0.32 at full size.
    double min_coverage = 0.25;
    double max_credible_error_mm = 0.5; // beyond it the certificate is refused
    MaximumPermissibleErrors mpe;
};

struct MeasuredSphere {
    std::size_t index = 0;         // the artefact's sphere (0-based)
    double certified_diameter = 0; // mm
    Vec3 centre{};
    double diameter = 0;
    double form = 0;            // P_F, the guideline's 0.3 % excluded
    double form_all_points = 0; // the range over every used point
    double size_error = 0;      // P_S
    double rms = 0;             // RMS radial residual
    double coverage = 0;        // share of the hemisphere facing the camera
    std::size_t points_used = 0;
    std::vector<std::uint32_t> pixels; // the used points' camera pixels
    std::vector<double> residuals;     // radial, per used point, + outside
    std::optional<Vec3> truth_centre;  // with ground truth: fitted to the true points
};

struct MeasuredPlane {
    double flatness = 0;            // F, the guideline's 0.3 % excluded
    double flatness_all_points = 0; // over every used point
    double rms = 0;
    double extent_mm[2] = {0, 0};
    std::size_t points_used = 0;
    std::vector<std::uint32_t> pixels;
    std::vector<double> residuals; // signed, + towards the camera
};

struct MeasuredPosition {
    std::filesystem::path capture; // the capture set's folder
    Size camera;
    std::vector<MeasuredSphere> spheres;       // in the artefact's order
    std::optional<double> length;              // ball bar: centre distance
    std::optional<double> spacing_error;       // SD
    std::optional<double> truth_spacing_error; // SD of the true points' spheres
    std::optional<MeasuredPlane> plane;
};

// The artefact in one position's cloud (xyz: 3 channels, camera frame, mm,
// NaN = no point; `truth_xyz` the simulator's true points of the same
// pixels, or empty). Throws InputError(capture, "sphere N" or "plane", why)
// for the refusals of a position above.
MeasuredPosition measure_position(const Artefact& artefact, const Image<float>& xyz,
                                  const std::filesystem::path& capture,
                                  const VerificationOptions& options,
                                  const Image<float>& truth_xyz = {});

// Throws InputError(artefact file, key, why) when the scans contradict the
// certificate beyond options.max_credible_error_mm.
void check_certificate(const Artefact& artefact, const std::vector<MeasuredPosition>& positions,
                       const VerificationOptions& options);

// One figure against its MPE.
struct FigureVerdict {
    std::string name;           // "SD", "P_F", "P_S", "F"
    std::vector<double> values; // every value of it, in position order
    double worst = 0;           // largest |value|
    std::optional<double> mpe;  // none: no verdict
    bool passed() const { return !mpe || worst <= *mpe; }
};

// The figures the artefact gives (ball bar: SD, P_F, P_S; sphere: P_F, P_S;
// plane: F), each with its verdict.
std::vector<FigureVerdict> verdicts(const Artefact& artefact,
                                    const std::vector<MeasuredPosition>& positions,
                                    const MaximumPermissibleErrors& mpe);

} // namespace fpp::calib
