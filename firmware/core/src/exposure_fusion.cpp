#include "fpp/exposure_fusion.hpp"

#include "fpp/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fpp {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Passes agree when their coordinates differ by at most this many combined sigma.
constexpr float kAgreeSigmas = 3.0f;

void fit(Image<float>& image, Size size, bool wanted) {
    if (!wanted) {
        image = Image<float>();
        return;
    }
    if (image.size() != size || image.channels() != 1)
        image = Image<float>(size, 1, kNaN);
}

struct WorkerStats {
    std::vector<std::size_t> reference;
    std::size_t averaged = 0, disagreeing = 0, undecoded = 0;
};

} // namespace

FusionStats fuse_exposures(const std::vector<ExposurePass>& passes, DecodeResult& out,
                           Image<float>& sigma, ThreadPool* pool) {
    if (passes.empty())
        throw std::invalid_argument("fuse_exposures: no pass");
    const Size size = passes[0].decoded.camera;
    const bool has_x = !passes[0].decoded.proj_x.empty();
    const bool has_y = !passes[0].decoded.proj_y.empty();
    for (const ExposurePass& p : passes) {
        const DecodeResult& d = p.decoded;
        if (d.camera != size || d.mask.size() != size || d.proj_x.empty() != !has_x ||
            d.proj_y.empty() != !has_y || d.modulation.size() != size || d.mean.size() != size)
            throw std::invalid_argument("fuse_exposures: passes of different sizes or axes");
        if (p.sigma.size() != size || p.sigma.channels() != 1)
            throw std::invalid_argument("fuse_exposures: a sigma image of another size");
        if (!(p.exposure_us > 0))
            throw std::invalid_argument("fuse_exposures: exposure must be positive");
    }
    out.camera = size;
    out.method_x = passes[0].decoded.method_x;
    out.method_y = passes[0].decoded.method_y;
    fit(out.proj_x, size, has_x);
    fit(out.proj_y, size, has_y);
    fit(out.modulation, size, true);
    fit(out.mean, size, true);
    fit(sigma, size, true);
    if (out.mask.size() != size)
        out.mask = Image<std::uint8_t>(size, 1, 0);

    ThreadPool& workers = pool ? *pool : ThreadPool::shared();
    std::vector<WorkerStats> stats(static_cast<std::size_t>(workers.size()));
    for (WorkerStats& s : stats)
        s.reference.assign(passes.size(), 0);
    const double first_exposure = passes[0].exposure_us;
    const std::size_t n_pass = passes.size();
    const int rows = size.height;
    workers.parallel_for(
        rows, std::max(1, rows / (8 * workers.size())), [&](int y0, int y1, int worker) {
            WorkerStats& st = stats[static_cast<std::size_t>(worker)];
            for (int y = y0; y < y1; ++y) {
                for (int x = 0; x < size.width; ++x) {
                    const std::size_t i = static_cast<std::size_t>(y) * size.width + x;
                    // The reference: the decoded pass with the smallest sigma.
                    std::size_t best = n_pass;
                    float best_sigma = std::numeric_limits<float>::infinity();
                    std::uint8_t flags = 0;
                    for (std::size_t k = 0; k < n_pass; ++k) {
                        const std::uint8_t f = passes[k].decoded.mask.data()[i];
                        flags |= f;
                        const float s = passes[k].sigma.data()[i];
                        if ((f & kDecodeValid) && s < best_sigma) {
                            best = k;
                            best_sigma = s;
                        }
                    }
                    if (best == n_pass) {
                        out.mask.data()[i] = static_cast<std::uint8_t>(flags & ~kDecodeValid);
                        if (has_x)
                            out.proj_x.data()[i] = kNaN;
                        if (has_y)
                            out.proj_y.data()[i] = kNaN;
                        out.modulation.data()[i] = kNaN;
                        out.mean.data()[i] = kNaN;
                        sigma.data()[i] = kNaN;
                        ++st.undecoded;
                        continue;
                    }
                    const DecodeResult& ref = passes[best].decoded;
                    const float ref_x = has_x ? ref.proj_x.data()[i] : 0.0f;
                    const float ref_y = has_y ? ref.proj_y.data()[i] : 0.0f;
                    double wsum = 0, sx = 0, sy = 0;
                    int used = 0;
                    for (std::size_t k = 0; k < n_pass; ++k) {
                        const DecodeResult& d = passes[k].decoded;
                        if (!(d.mask.data()[i] & kDecodeValid))
                            continue;
                        const float s = passes[k].sigma.data()[i];
                        if (!(s > 0.0f) || !std::isfinite(s))
                            continue;
                        const float limit =
                            kAgreeSigmas * std::sqrt(s * s + best_sigma * best_sigma);
                        const float px = has_x ? d.proj_x.data()[i] : 0.0f;
                        const float py = has_y ? d.proj_y.data()[i] : 0.0f;
                        if (std::fabs(px - ref_x) > limit || std::fabs(py - ref_y) > limit) {
                            ++st.disagreeing;
                            continue;
                        }
                        const double w = 1.0 / (double(s) * double(s));
                        wsum += w;
                        sx += w * double(px);
                        sy += w * double(py);
                        ++used;
                    }
                    ++st.reference[best];
                    if (used > 1)
                        ++st.averaged;
                    const bool weighted = wsum > 0;
                    if (has_x)
                        out.proj_x.data()[i] = weighted ? static_cast<float>(sx / wsum) : ref_x;
                    if (has_y)
                        out.proj_y.data()[i] = weighted ? static_cast<float>(sy / wsum) : ref_y;
                    sigma.data()[i] =
                        weighted ? static_cast<float>(1.0 / std::sqrt(wsum)) : best_sigma;
                    const float scale =
                        static_cast<float>(first_exposure / passes[best].exposure_us);
                    out.modulation.data()[i] = ref.modulation.data()[i] * scale;
                    out.mean.data()[i] = ref.mean.data()[i] * scale;
                    out.mask.data()[i] = ref.mask.data()[i];
                }
            }
        });
    FusionStats total;
    total.reference_pixels.assign(n_pass, 0);
    for (const WorkerStats& s : stats) {
        for (std::size_t k = 0; k < n_pass; ++k)
            total.reference_pixels[k] += s.reference[k];
        total.averaged += s.averaged;
        total.disagreeing += s.disagreeing;
        total.undecoded += s.undecoded;
    }
    return total;
}

} // namespace fpp
