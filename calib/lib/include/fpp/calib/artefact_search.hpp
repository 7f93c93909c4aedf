#pragma once
// Finding a certified artefact's elements (spheres of a known diameter, a
// flat plate of a known size) in an organised cloud that holds other
// surfaces too: the bar between a ball bar's spheres, its stand, a wall
// behind. Camera frame, mm; pixel = row * width + column.
//
// Spheres are found by their shape and the certificate's radius r, not by
// being alone in view:
//   1. usable points: finite, and more than `edge_margin_px` pixels from a
//      hole or a depth jump (a neighbour further in depth than
//      `depth_jump_footprints` times the pixel's footprint): a pixel that
//      straddles a sphere's silhouette and the surface behind mixes both
//      surfaces' fringes and lies between them;
//   2. every usable point votes for the centre of a sphere of radius r
//      through it, p - r n (n its normal from the points r/4 either side,
//      towards the camera), in cells of r/5, when the points r/4 either
//      side name the same centre (within 0.15 r): on a sphere of that
//      radius they do, on a plane or a bar they stand a chord apart, so
//      flat and singly curved surfaces cast no votes;
//   3. each peak (strongest first, none within r of a stronger one) is fitted:
//      the points within max(1 mm, 0.15 r) of the shell of radius r about
//      it, a least-squares sphere of free radius with outliers beyond 3 sigma
//      rejected, then twice the points within max(5 sigma, 0.05 mm) of that
//      sphere, 5 sigma (sigma: 1.4826 x the median |residual|) far beyond the
//      noise but well inside the distance to any other surface, less those
//      whose normal is more than 20 degrees off the sphere's radius (the bar
//      where it meets the sphere), refitted.
// A peak is a sphere of the certificate when its fitted diameter is within
// max(1 mm, 10 %) of the certified one (the certificate's consistency with
// the scans is judged later, fpp/calib/verification.hpp).
//
// Coverage: the share of the hemisphere facing the camera that the used
// points cover, in 156 cells of equal area (a 14 x 14 grid over the
// hemisphere's Lambert azimuthal equal-area map). Points within a few
// pixels of the silhouette are not used, so a whole sphere scores less than
// 1: about 0.5 at 42 px across (400 x 300 at 480 mm), 0.6 at 800 x 600,
// 0.7 at full size (1600 x 1200).

#include "fpp/calib/evaluation.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace fpp::calib {

struct ArtefactSearchOptions {
    int edge_margin_px = 2;
    double depth_jump_footprints = 8;
    std::size_t min_points = 30;     // a sphere or plane fitted from fewer is not one
    std::size_t min_votes = 10;      // a vote peak with fewer is not fitted
    std::size_t max_candidates = 12; // vote peaks fitted per radius
};

// 1 where a point is usable (step 1 above); xyz: 3 channels, NaN = none.
std::vector<std::uint8_t> usable_points(const Image<float>& xyz,
                                        const ArtefactSearchOptions& options = {});

struct FoundSphere {
    ProbingFigures figures;            // fit of free radius; P_S against the certified diameter
    std::vector<std::uint32_t> pixels; // of the used points
    std::vector<Vec3> points;          // the used points
    double coverage = 0;               // share of the hemisphere facing the camera
    std::size_t gathered = 0;          // points near the shell before the final selection
    std::size_t votes = 0;             // the peak's votes
};

// Every sphere of `diameter_mm` in the cloud (steps 2 and 3), strongest
// first; `usable` from usable_points. Spheres whose centres are closer than
// the radius are one (the one with more points is kept).
std::vector<FoundSphere> find_spheres(const Image<float>& xyz, std::span<const std::uint8_t> usable,
                                      double diameter_mm,
                                      const ArtefactSearchOptions& options = {});

// Share of the hemisphere of the sphere about `centre` facing the camera
// (the origin) that holds at least one of `points`, as above.
double hemisphere_coverage(std::span<const Vec3> points, const Vec3& centre);

struct FoundPlane {
    FlatnessFigures figures;
    std::vector<std::uint32_t> pixels;
    std::vector<Vec3> points;
    double extent_mm[2] = {0, 0}; // along the plane's principal directions, larger first
};

// The flat of `width` x `height` mm: of the planes in the cloud (RANSAC,
// largest first, each the biggest connected patch of points within
// max(5 sigma, 0.05 mm) of its fit), the first whose extent fits the
// plate's (within 5 mm). Throws FitError saying what was found otherwise.
FoundPlane find_plane(const Image<float>& xyz, std::span<const std::uint8_t> usable,
                      double width_mm, double height_mm, const ArtefactSearchOptions& options = {});

} // namespace fpp::calib
