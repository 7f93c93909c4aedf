#pragma once
// Checkerboard inner corners in the camera image of a calibration capture.
//
// Ordering: corner (i, j), i < columns, j < rows, is stored at index
// j * columns + i, and (i, j) always names the same physical corner of the
// board in every pose:
//   - handedness: seen from the camera, i runs "right" and j "down" on the
//     board (the board's normal, x cross y, points away from the camera), so
//     the board frame is right-handed with the board in front;
//   - boards that are not symmetric under a half turn (columns + rows odd):
//     corner (0, 0) is the one whose diagonally outside square is black (the
//     convention of fpp::sim::Checkerboard), told by the texture;
//   - symmetric boards (columns + rows even): the two half-turn orderings
//     are indistinguishable on the board itself, and corner (0, 0) is the
//     one nearer the image's top-left corner (valid while the board is not
//     turned in its plane by more than ~45 degrees between poses).
// Coordinates are camera pixels, pixel centres on integers.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <string>
#include <vector>

namespace fpp::calib {

// The image corners are found on, and where it came from.
struct CornerTexture {
    Image<float> image; // camera size, DN
    std::string source; // "white frame", "phase mean", ...
};

// Textures for corner finding, preferred first: the `white` frame when the
// sequence has one; the mean of every phase-shifted frame ("phase mean": the
// only texture of captures without a white frame, such as SLStudio's, and
// the less noisy one, being an average); the fringe maximum A + B of the
// decoded finest block ("phase mean + modulation", a last resort for finding
// the board: under a projector gamma its fringe residue biases corners by
// ~0.05 px with 3-step phase, measured in simulation).
std::vector<CornerTexture> corner_textures(const CaptureSet& capture, const DecodeResult& decoded);

enum class CornerRefinement {
    subpix, // cv::cornerSubPix (gradients orthogonal to the corner offset)
    model,  // cornerSubPix, then a least-squares fit of a blurred checker
            // corner model (below) to the pixels around each corner
};

struct CornerFinderOptions {
    bool classic = true; // cv::findChessboardCorners (histogram and global thresholds)
    bool sector = true;  // cv::findChessboardCornersSB, tried when classic fails
    // Half-size of the cornerSubPix window, px; 0 = a fifth of the smallest
    // corner spacing, at least 3.
    int refine_half_window = 0;
    CornerRefinement refinement = CornerRefinement::model;
};

struct CheckerboardCorners {
    bool found = false;
    std::string finder;       // "classic" or "sector"
    std::string texture;      // CornerTexture::source the board was found on
    std::string failure;      // why not found (empty if found)
    std::vector<Vec2> points; // columns * rows, ordering above
    // Whether the square diagonally outside corner (0, 0) is black, as
    // measured on the texture (used to pick the white squares around each corner).
    bool origin_square_black = true;
    double spacing_px = 0; // median distance between neighbouring corners
    // The detector's work: finder runs made, over every texture tried (at
    // most 2 a texture), and the factor by which the image they found the
    // board on was reduced (1: the texture itself; 0 when not found).
    int detector_attempts = 0;
    int detector_factor = 0;
};

// Finds, refines and orders the inner corners. Tries the classic finder then
// the sector-based one on each texture in turn, once each, on a copy reduced
// to at most 1000 px a side with its shading divided out (a strongly tilted
// or unevenly lit board costs the detector about what a frontal one does:
// no adaptive-threshold retries, no search of the full-size image, so a
// board is found at that size or not at all); the corners are refined at
// full size on the first (preferred) texture whichever one the board was
// found on. A corner farther than a tenth of the
// spacing (at least 2 px) from where its neighbours put it (the board's four
// outer corners included) is sought again there; if it is still off, that
// detection is refused and the next finder or texture tried (the failure
// names the corner).
CheckerboardCorners find_checkerboard(const std::vector<CornerTexture>& textures, int columns,
                                      int rows, const CornerFinderOptions& options = {});

// Reorders a grid of columns x rows corners (row-major as OpenCV returns it)
// by the rules above; `texture` tells the colour of squares. Returns whether
// the square diagonally outside corner (0, 0) is black.
bool canonical_corner_order(std::vector<Vec2>& points, int columns, int rows,
                            const Image<float>& texture);

// Refines corners (ordering above) by fitting, in a disc around each corner,
//   I(x) = a0 + ax dx + ay dy
//          + b (1 + gx dx + gy dy) erf(d1 / (sqrt(2) s)) erf(d2 / (sqrt(2) s)),
// d1, d2 the signed distances of x to the two edges through the corner
// (free directions: perspective shears the corner), s the blur, a0 ax ay b
// the shading: the maximum-likelihood corner under white noise, using every
// pixel of the four squares' inner parts rather than gradients alone. A first
// pass takes the edges straight (d = l) and the contrast flat (g = 0); a
// second bends each edge as the cubic through its row or column of corners
// bends (d = l + k w^2, w along the edge) and tilts the contrast as the
// neighbours' fitted contrasts say. A fit that fails or moves a corner by
// more than `max_shift_px` leaves it as it was. Sharp images (median fitted
// blur below 0.4 px: edges are then box-sampled ramps rather than erf
// profiles, and the fit of nearly axis-aligned edges jumps with the
// sub-pixel phase) are fitted after a 0.5 px Gaussian pre-blur, which keeps
// the corner where it is (the pattern is symmetric about it).
// Returns the number of corners refined.
int refine_corners_model(const Image<float>& texture, std::vector<Vec2>& points, int columns,
                         int rows, double max_shift_px = 2.0);

// Mean texture value at board position (a, b), in square units relative to
// corner (0, 0), found through the local affine frame of the nearest corners
// (for colour tests); NaN outside the image.
double texture_at_board(const std::vector<Vec2>& points, int columns, int rows,
                        const Image<float>& texture, double a, double b);

} // namespace fpp::calib
