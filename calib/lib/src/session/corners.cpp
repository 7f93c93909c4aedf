// Checkerboard corners: texture, detection (OpenCV's classic and sector-based
// finders), sub-pixel refinement and a pose-independent ordering.

#include "fpp/calib/corners.hpp"

#include "corner_detect.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <variant>

namespace fpp::calib {

namespace {

Image<float> frame_to_float(const Frame& frame) {
    const Size s = frame.size();
    Image<float> out(s);
    float* dst = out.data();
    const std::size_t n = s.area();
    if (frame.bit_depth == 8) {
        const std::uint8_t* src = frame.u8.data();
        for (std::size_t i = 0; i < n; ++i)
            dst[i] = static_cast<float>(src[i]);
    } else {
        const std::uint16_t* src = frame.u16.data();
        for (std::size_t i = 0; i < n; ++i)
            dst[i] = static_cast<float>(src[i]);
    }
    return out;
}

cv::Mat as_mat(const Image<float>& image) {
    return cv::Mat(image.height(), image.width(), CV_32F, const_cast<float*>(image.data()));
}

double dist(const Vec2& a, const Vec2& b) {
    return std::hypot(a[0] - b[0], a[1] - b[1]);
}

// Median and minimum distance between grid neighbours.
void neighbour_spacing(const std::vector<Vec2>& p, int columns, int rows, double& median,
                       double& minimum) {
    std::vector<double> d;
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const std::size_t k = static_cast<std::size_t>(j * columns + i);
            if (i + 1 < columns)
                d.push_back(dist(p[k], p[k + 1]));
            if (j + 1 < rows)
                d.push_back(dist(p[k], p[k + static_cast<std::size_t>(columns)]));
        }
    std::sort(d.begin(), d.end());
    median = d.empty() ? 0 : d[d.size() / 2];
    minimum = d.empty() ? 0 : d.front();
}

std::vector<Vec2> reordered(const std::vector<Vec2>& p, int columns, int rows, bool flip_i,
                            bool flip_j) {
    std::vector<Vec2> out(p.size());
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const int si = flip_i ? columns - 1 - i : i;
            const int sj = flip_j ? rows - 1 - j : j;
            out[static_cast<std::size_t>(j * columns + i)] =
                p[static_cast<std::size_t>(sj * columns + si)];
        }
    return out;
}

// Transposed grid (a square board found with rows and columns swapped).
std::vector<Vec2> transposed(const std::vector<Vec2>& p, int n) {
    std::vector<Vec2> out(p.size());
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            out[static_cast<std::size_t>(j * n + i)] = p[static_cast<std::size_t>(i * n + j)];
    return out;
}

double handedness(const std::vector<Vec2>& p, int columns, int rows) {
    const Vec2& o = p[0];
    const Vec2& a = p[static_cast<std::size_t>(columns - 1)];
    const Vec2& b = p[static_cast<std::size_t>((rows - 1) * columns)];
    const double ax = a[0] - o[0], ay = a[1] - o[1], bx = b[0] - o[0], by = b[1] - o[1];
    return ax * by - ay * bx; // > 0: i right, j down in image coordinates (y down)
}

// Dark-minus-light evidence that the square diagonally outside corner (0, 0)
// is black: the outside square against its neighbour along the top edge,
// checked at all four outer corners of the pattern (their expected colours
// follow from the parity of columns and rows).
double origin_black_evidence(const std::vector<Vec2>& p, int columns, int rows,
                             const Image<float>& texture) {
    double evidence = 0;
    const int ci[4] = {0, columns - 1, 0, columns - 1};
    const int cj[4] = {0, 0, rows - 1, rows - 1};
    for (int c = 0; c < 4; ++c) {
        // Outward diagonal square centre and its neighbour along the outer row.
        const double di = ci[c] == 0 ? -0.5 : 0.5, dj = cj[c] == 0 ? -0.5 : 0.5;
        const double outside = texture_at_board(p, columns, rows, texture, ci[c] + di, cj[c] + dj);
        const double beside = texture_at_board(p, columns, rows, texture, ci[c] - di, cj[c] + dj);
        if (!std::isfinite(outside) || !std::isfinite(beside))
            continue;
        // Square (m, n) is black when m + n is even (origin black); the
        // outside square of corner (ci, cj) is square (ci + (di > 0), cj + (dj > 0)).
        const int m = ci[c] + (di > 0 ? 1 : 0), n = cj[c] + (dj > 0 ? 1 : 0);
        const bool black_if_origin_black = (m + n) % 2 == 0;
        const double dark_outside = beside - outside; // > 0 when the outside square is darker
        evidence += black_if_origin_black ? dark_outside : -dark_outside;
    }
    return evidence;
}

} // namespace

std::vector<CornerTexture> corner_textures(const CaptureSet& capture, const DecodeResult& decoded) {
    std::vector<CornerTexture> textures;
    // The white frame, and the mean of every phase-shifted frame (each N-step
    // block sums to N times the mean intensity A: a texture at half the
    // white level, with noise averaged over all of them).
    Image<float> phase_mean;
    int frame = 0, phase_frames = 0;
    for (const PatternBlock& block : capture.manifest.sequence) {
        const int count = frame_count(block);
        if (static_cast<std::size_t>(frame + count) > capture.frames.size())
            break;
        if (std::holds_alternative<WhiteBlock>(block) && textures.empty()) {
            textures.push_back(
                {frame_to_float(capture.frames[static_cast<std::size_t>(frame)]), "white frame"});
        } else if (std::holds_alternative<PhaseBlock>(block)) {
            for (int k = 0; k < count; ++k) {
                const Frame& f = capture.frames[static_cast<std::size_t>(frame + k)];
                if (phase_mean.empty())
                    phase_mean = Image<float>(f.size());
                float* dst = phase_mean.data();
                const std::size_t n = phase_mean.pixel_count();
                if (f.bit_depth == 8) {
                    const std::uint8_t* src = f.u8.data();
                    for (std::size_t i = 0; i < n; ++i)
                        dst[i] += static_cast<float>(src[i]);
                } else {
                    const std::uint16_t* src = f.u16.data();
                    for (std::size_t i = 0; i < n; ++i)
                        dst[i] += static_cast<float>(src[i]);
                }
                ++phase_frames;
            }
        }
        frame += count;
    }
    if (phase_frames > 0) {
        const float inv = 1.0f / static_cast<float>(phase_frames);
        for (float& v : phase_mean.storage())
            v *= inv;
        textures.push_back({std::move(phase_mean), "phase mean"});
    }
    // Last resort for finding the board only (its fringe residue under a
    // projector gamma biases corners): the fringe maximum A + B.
    if (!decoded.mean.empty() && !decoded.modulation.empty() &&
        decoded.mean.size() == decoded.modulation.size()) {
        Image<float> peak(decoded.mean.size());
        const std::size_t n = peak.pixel_count();
        for (std::size_t i = 0; i < n; ++i)
            peak.data()[i] = decoded.mean.data()[i] + decoded.modulation.data()[i];
        textures.push_back({std::move(peak), "phase mean + modulation"});
    }
    return textures;
}

double texture_at_board(const std::vector<Vec2>& p, int columns, int rows,
                        const Image<float>& texture, double a, double b) {
    const int i = std::clamp(static_cast<int>(std::lround(a)), 0, columns - 1);
    const int j = std::clamp(static_cast<int>(std::lround(b)), 0, rows - 1);
    auto at = [&](int ii, int jj) { return p[static_cast<std::size_t>(jj * columns + ii)]; };
    const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, columns - 1);
    const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, rows - 1);
    const Vec2 c = at(i, j);
    const Vec2 di{(at(i1, j)[0] - at(i0, j)[0]) / (i1 - i0),
                  (at(i1, j)[1] - at(i0, j)[1]) / (i1 - i0)};
    const Vec2 dj{(at(i, j1)[0] - at(i, j0)[0]) / (j1 - j0),
                  (at(i, j1)[1] - at(i, j0)[1]) / (j1 - j0)};
    const double x = c[0] + (a - i) * di[0] + (b - j) * dj[0];
    const double y = c[1] + (a - i) * di[1] + (b - j) * dj[1];
    // Mean over a box of a fifth of a square.
    const int r = std::max(
        1, static_cast<int>(0.1 * std::min(std::hypot(di[0], di[1]), std::hypot(dj[0], dj[1]))));
    const int xc = static_cast<int>(std::lround(x)), yc = static_cast<int>(std::lround(y));
    if (xc - r < 0 || yc - r < 0 || xc + r >= texture.width() || yc + r >= texture.height())
        return std::numeric_limits<double>::quiet_NaN();
    double sum = 0;
    int count = 0;
    for (int yy = yc - r; yy <= yc + r; ++yy)
        for (int xx = xc - r; xx <= xc + r; ++xx) {
            const float v = texture.at(xx, yy);
            if (std::isfinite(v)) {
                sum += static_cast<double>(v);
                ++count;
            }
        }
    return count ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

bool canonical_corner_order(std::vector<Vec2>& p, int columns, int rows,
                            const Image<float>& texture) {
    // Handedness first: a mirrored grid is flipped along i.
    if (handedness(p, columns, rows) < 0)
        p = reordered(p, columns, rows, true, false);
    // Candidates related by rotations of the pattern onto itself.
    std::vector<std::vector<Vec2>> candidates{p, reordered(p, columns, rows, true, true)};
    if (columns == rows) {
        // Quarter turns of a square pattern: transpose plus a flip keeps handedness.
        const std::vector<Vec2> t = reordered(transposed(p, columns), columns, rows, true, false);
        candidates.push_back(t);
        candidates.push_back(reordered(t, columns, rows, true, true));
    }
    const bool colour_decides = (columns + rows) % 2 == 1;
    std::size_t best = 0;
    double best_score = -std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < candidates.size(); ++c) {
        double score;
        if (colour_decides) {
            score = origin_black_evidence(candidates[c], columns, rows, texture);
        } else {
            const Vec2& o = candidates[c][0];
            score = -(o[0] + o[1]); // nearest the image's top-left
        }
        if (score > best_score) {
            best_score = score;
            best = c;
        }
    }
    p = candidates[best];
    return origin_black_evidence(p, columns, rows, texture) >= 0;
}

namespace {

// Where the neighbours put corner (i, j): the component-wise median of the
// midpoints of its row and column neighbours and of the extrapolations from
// two neighbours on each side (perspective moves a midpoint by a few
// hundredths of the spacing; one bad neighbour cannot carry the median). The
// board's four outer corners have only two of those, and also get the
// parallelogram of their three diagonal neighbours: without a third, one of
// them was let through 14 px off (a classic detection of a 45-degree tilt).
bool predicted_corner(const std::vector<cv::Point2f>& p, int columns, int rows, int i, int j,
                      cv::Point2f& out) {
    auto at = [&](int ii, int jj) { return p[static_cast<std::size_t>(jj * columns + ii)]; };
    auto inside = [&](int ii, int jj) { return ii >= 0 && jj >= 0 && ii < columns && jj < rows; };
    // At most six predictions: a midpoint and two extrapolations per axis.
    std::array<float, 6> xs{}, ys{};
    std::size_t count = 0;
    auto add = [&](cv::Point2f q) {
        xs[count] = q.x;
        ys[count] = q.y;
        ++count;
    };
    for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (inside(i - di, j - dj) && inside(i + di, j + dj))
            add(0.5f * (at(i - di, j - dj) + at(i + di, j + dj)));
        for (const int sign : {-1, 1})
            if (inside(i + 2 * sign * di, j + 2 * sign * dj))
                add(2.0f * at(i + sign * di, j + sign * dj) -
                    at(i + 2 * sign * di, j + 2 * sign * dj));
    }
    if (count == 2)
        for (const int si : {-1, 1})
            for (const int sj : {-1, 1})
                if (count < 3 && inside(i + si, j + sj) && inside(i + si, j) && inside(i, j + sj))
                    add(at(i + si, j) + at(i, j + sj) - at(i + si, j + sj));
    if (count < 3)
        return false;
    auto median = [count](std::array<float, 6>& v) {
        const auto middle = v.begin() + static_cast<std::ptrdiff_t>(count / 2);
        std::nth_element(v.begin(), middle, v.begin() + static_cast<std::ptrdiff_t>(count));
        return *middle;
    };
    out = {median(xs), median(ys)};
    return true;
}

// OpenCV's finders now and then leave a corner far from where its
// neighbours put it (cornerSubPix stuck on the wrong feature: 15 px off in
// one simulated pose). Such a corner is placed where its neighbours predict
// and refined again; false if one still disagrees, naming it in `why`.
bool repair_outlying_corners(const cv::Mat& texture, std::vector<cv::Point2f>& found, int columns,
                             int rows, double spacing, int half, std::string& why) {
    const double tolerance = std::max(2.0, 0.1 * spacing);
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            cv::Point2f expected;
            if (!predicted_corner(found, columns, rows, i, j, expected))
                continue;
            cv::Point2f& corner = found[static_cast<std::size_t>(j * columns + i)];
            if (cv::norm(corner - expected) <= tolerance)
                continue;
            std::vector<cv::Point2f> one{expected};
            cv::cornerSubPix(
                texture, one, cv::Size(half, half), cv::Size(-1, -1),
                cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
            if (!(cv::norm(one[0] - expected) <= tolerance)) {
                why = "corner (" + std::to_string(i) + ", " + std::to_string(j) + ") is " +
                      std::to_string(cv::norm(corner - expected)) +
                      " px from where its neighbours put it";
                return false;
            }
            corner = one[0];
        }
    return true;
}

} // namespace

CheckerboardCorners find_checkerboard(const std::vector<CornerTexture>& textures, int columns,
                                      int rows, const CornerFinderOptions& options) {
    CheckerboardCorners result;
    if (textures.empty()) {
        result.failure = "no texture to find the board on (no white frame and no phase)";
        return result;
    }
    std::vector<cv::Point2f> found;
    std::string tried;
    for (const CornerTexture& texture : textures) {
        const int factor = detail::detector_factor(texture.image.size());
        const cv::Mat image8 = detail::detector_image(texture.image, factor);
        for (const detail::Finder finder : {detail::Finder::classic, detail::Finder::sector}) {
            const bool sector = finder == detail::Finder::sector;
            if ((sector && !options.sector) || (!sector && !options.classic))
                continue;
            if (!tried.empty())
                tried += ", ";
            tried += (sector ? "sector" : "classic") + std::string(" on ") + texture.source;
            ++result.detector_attempts;
            if (!detail::run_finder(image8, factor, columns, rows, finder, found))
                continue;
            std::vector<Vec2> points(found.size());
            for (std::size_t k = 0; k < found.size(); ++k)
                points[k] = {static_cast<double>(found[k].x), static_cast<double>(found[k].y)};
            double median = 0, minimum = 0;
            neighbour_spacing(points, columns, rows, median, minimum);
            if (!(minimum > 4))
                continue; // degenerate detection
            // Sub-pixel refinement on the float texture; the window stays
            // well inside the nearest neighbouring squares.
            const int half = options.refine_half_window > 0
                                 ? options.refine_half_window
                                 : std::max(3, static_cast<int>(0.2 * minimum));
            // Refined on the preferred texture (the first), whichever one the
            // board was found on.
            const Image<float>& refine_on = textures.front().image;
            cv::Mat texture_mat = as_mat(refine_on).clone();
            cv::patchNaNs(texture_mat, 0.0);
            cv::cornerSubPix(
                texture_mat, found, cv::Size(half, half), cv::Size(-1, -1),
                cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
            std::string why;
            if (!repair_outlying_corners(texture_mat, found, columns, rows, median, half, why)) {
                tried += " (" + why + ")";
                continue;
            }
            for (std::size_t k = 0; k < found.size(); ++k)
                points[k] = {static_cast<double>(found[k].x), static_cast<double>(found[k].y)};
            bool finite = true;
            for (const Vec2& q : points)
                finite = finite && std::isfinite(q[0]) && std::isfinite(q[1]);
            if (!finite)
                continue;
            if (options.refinement == CornerRefinement::model)
                refine_corners_model(refine_on, points, columns, rows);
            result.origin_square_black = canonical_corner_order(points, columns, rows, refine_on);
            result.points = std::move(points);
            result.found = true;
            result.finder = sector ? "sector" : "classic";
            result.texture = texture.source;
            result.spacing_px = median;
            result.detector_factor = factor;
            return result;
        }
    }
    result.failure = "no " + std::to_string(columns) + " x " + std::to_string(rows) +
                     " checkerboard found (tried " + tried + ")";
    return result;
}

} // namespace fpp::calib
