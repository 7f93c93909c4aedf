#include "fpp/simulator/renderer.hpp"

#include "blur.hpp"
#include "fpp/vec3.hpp"
#include "noise.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace fpp::sim {

using namespace vec;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Shadow rays start this far off the surface (mm), along its normal, so that
// they do not hit the surface they leave.
constexpr double kShadowOffset = 1e-6;

// Largest r^2 (normalised, undistorted) over the projector image's border,
// with a margin: beyond it the distortion polynomial may fold back into the
// image, so such points are not lit.
double projector_r2_limit(const Rig& rig) {
    const int W = rig.projector_size.width, H = rig.projector_size.height;
    double r2max = 0;
    auto visit = [&](double u, double v) {
        Vec2 n{};
        if (rig.projector.pixel_to_normalised({u, v}, n))
            r2max = std::max(r2max, n[0] * n[0] + n[1] * n[1]);
    };
    for (int i = 0; i <= 64; ++i) {
        const double u = -0.5 + W * i / 64.0, v = -0.5 + H * i / 64.0;
        visit(u, -0.5);
        visit(u, H - 0.5);
        visit(-0.5, v);
        visit(W - 0.5, v);
    }
    return 1.5 * r2max;
}

// Rows per parallel_for chunk: about eight chunks per worker, so that rows of
// uneven cost (ray casting) spread over the workers.
int row_grain(int rows, const ThreadPool& pool) {
    return std::max(1, rows / (8 * pool.size()));
}

} // namespace

Renderer::Renderer(const Rig& rig, const Scene& scene, int threads)
    : rig_(rig), pool_(std::make_shared<ThreadPool>(threads)) {
    rig_.validate();
    const int W = rig_.camera_size.width, H = rig_.camera_size.height;
    const int PW = rig_.projector_size.width, PH = rig_.projector_size.height;
    truth_xyz_ = Image<float>(W, H, 3, kNaN);
    truth_projector_ = Image<float>(W, H, 2, kNaN);
    truth_object_ = Image<std::int32_t>(W, H, 1, kNoObject);
    object_names_.reserve(scene.size());
    for (std::size_t k = 0; k < scene.size(); ++k)
        object_names_.push_back(scene.object_name(k));
    radiance_gain_ = Image<float>(W, H, 1, 0.0f);
    ambient_ = Image<float>(W, H, 1, 0.0f);
    albedo_ = Image<float>(W, H, 1, 0.0f);
    sample_index_.assign(rig_.camera_size.area(), 0);
    sample_fx_.assign(rig_.camera_size.area(), 0.0f);
    sample_fy_.assign(rig_.camera_size.area(), 0.0f);

    const LensModel& cam = rig_.camera;
    const LensModel& proj = rig_.projector;
    const Vec3 proj_centre = rig_.projector_centre_in_camera();
    const double r2_limit = projector_r2_limit(rig_);
    const SensorModel& sensor = rig_.sensor;
    // d(distorted)/d(pixel) of the camera: the inverse of its linear part.
    const double dxd_du = 1 / cam.fu, dxd_dv = -cam.skew / (cam.fu * cam.fv), dyd_dv = 1 / cam.fv;

    pool_->parallel_for(H, row_grain(H, *pool_), [&](int y0, int y1, int) {
        for (int y = y0; y < y1; ++y) {
            for (int x = 0; x < W; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * W + x;
                Vec2 n{};
                if (!cam.pixel_to_normalised({double(x), double(y)}, n))
                    continue;
                const Vec3 D{n[0], n[1], 1.0};
                const double lenD = norm(D);
                const Vec3 d = scale(D, 1 / lenD);
                Hit hit;
                if (!scene.intersect({0, 0, 0}, d, hit))
                    continue;

                // Ray differentials: dn/dpixel = J^-1 d(distorted)/d(pixel).
                const Mat2 J = cam.distortion_jacobian(n);
                const double det = J[0] * J[3] - J[1] * J[2];
                const Vec2 dn_du{J[3] * dxd_du / det, -J[2] * dxd_du / det};
                const Vec2 dn_dv{(J[3] * dxd_dv - J[1] * dyd_dv) / det,
                                 (-J[2] * dxd_dv + J[0] * dyd_dv) / det};
                auto direction_change = [&](const Vec2& dn) {
                    const Vec3 dD{dn[0], dn[1], 0.0};
                    return scale(sub(dD, scale(d, dot(d, dD))), 1 / lenD);
                };
                // Surface displacement per pixel: move along the ray to stay on the tangent plane.
                const double dn_dot = dot(d, hit.normal);
                double albedo = hit.albedo;
                if (std::fabs(dn_dot) > 1e-6) {
                    auto on_surface = [&](const Vec3& dd) {
                        const Vec3 dp = scale(dd, hit.t);
                        return sub(dp, scale(d, dot(dp, hit.normal) / dn_dot));
                    };
                    albedo = scene.shape(static_cast<std::size_t>(hit.object))
                                 .footprint_albedo(hit, on_surface(direction_change(dn_du)),
                                                   on_surface(direction_change(dn_dv)));
                }
                float* xyz = truth_xyz_.row(y) + 3 * x;
                xyz[0] = static_cast<float>(hit.point[0]);
                xyz[1] = static_cast<float>(hit.point[1]);
                xyz[2] = static_cast<float>(hit.point[2]);
                truth_object_.row(y)[x] = hit.object;
                const SpecularLobe& lobe = scene.specular(static_cast<std::size_t>(hit.object));
                albedo_.row(y)[x] = static_cast<float>(albedo);
                // Without a lobe the sums add an exact 0: renders stay bit-identical.
                ambient_.row(y)[x] = static_cast<float>(sensor.ambient * (albedo + lobe.specular));

                // Projector pixel lighting the point, through the distorted projector model.
                const Vec3 Xp = add(mul(rig_.R, hit.point), rig_.t);
                if (!(Xp[2] > 0))
                    continue;
                const Vec2 np{Xp[0] / Xp[2], Xp[1] / Xp[2]};
                if (np[0] * np[0] + np[1] * np[1] > r2_limit)
                    continue;
                const Vec2 pp = proj.distorted_to_pixel(proj.distort(np));
                if (!(pp[0] >= -0.5 && pp[0] <= PW - 0.5 && pp[1] >= -0.5 && pp[1] <= PH - 0.5))
                    continue;
                // Facing the projector and not shadowed.
                const Vec3 to_proj = sub(proj_centre, hit.point);
                const double dist = norm(to_proj);
                const Vec3 l = scale(to_proj, 1 / dist);
                const double cos_inc = dot(hit.normal, l);
                if (!(cos_inc > 0))
                    continue;
                const Vec3 start = add(hit.point, scale(hit.normal, kShadowOffset));
                if (scene.occluded(start, l, dist))
                    continue;

                const double falloff = sensor.reference_distance_mm > 0
                                           ? (sensor.reference_distance_mm / dist) *
                                                 (sensor.reference_distance_mm / dist)
                                           : 1.0;
                // Specular lobe: half vector of the directions to the
                // projector and to the camera (-d).
                double specular = 0;
                if (lobe.active()) {
                    const Vec3 h = normalised(sub(l, d));
                    specular = lobe.relative_reflectance(dot(hit.normal, h));
                }
                radiance_gain_.row(y)[x] = static_cast<float>(
                    sensor.white_level * (albedo + specular) * cos_inc * falloff);
                float* tp = truth_projector_.row(y) + 2 * x;
                tp[0] = static_cast<float>(pp[0]);
                tp[1] = static_cast<float>(pp[1]);
                // Bilinear sample (pixel centres on integers), clamped at the image edges.
                const double sx = std::clamp(pp[0], 0.0, PW - 1.0);
                const double sy = std::clamp(pp[1], 0.0, PH - 1.0);
                const int ix = std::min(static_cast<int>(sx), PW - 2);
                const int iy = std::min(static_cast<int>(sy), PH - 2);
                sample_index_[i] = static_cast<std::uint32_t>(iy * PW + ix);
                sample_fx_[i] = static_cast<float>(sx - ix);
                sample_fy_[i] = static_cast<float>(sy - iy);
            }
        }
    });
}

const std::string& Renderer::object_name(std::int32_t object) const {
    static const std::string none = "none";
    if (object == kNoObject)
        return none;
    if (object < 0 || static_cast<std::size_t>(object) >= object_names_.size())
        throw std::out_of_range("Renderer::object_name: no object " + std::to_string(object));
    return object_names_[static_cast<std::size_t>(object)];
}

void Renderer::set_threads(int threads) {
    pool_ = std::make_shared<ThreadPool>(threads);
}

std::uint64_t Renderer::frame_seed(std::uint64_t seed, int frame) {
    return detail::mix64(detail::mix64(seed) + static_cast<std::uint64_t>(frame) + 1);
}

namespace {

// Per-thread buffers reused from frame to frame: fresh multi-megabyte
// allocations would page-fault on every frame.
struct Scratch {
    std::vector<float> radiance, light, blur;
    std::vector<float> noisy_rows; // one camera row per pool worker
};

Scratch& thread_scratch() {
    thread_local Scratch scratch;
    return scratch;
}

} // namespace

void Renderer::radiance_into(const Image<std::uint8_t>& projector_image,
                             std::vector<float>& radiance, std::vector<float>& light,
                             std::vector<float>& blur) const {
    if (projector_image.size() != rig_.projector_size || projector_image.channels() != 1)
        throw std::invalid_argument("Renderer::render: projector image must be " +
                                    std::to_string(rig_.projector_size.width) + "x" +
                                    std::to_string(rig_.projector_size.height) + ", 1 channel");
    // Emitted light per projector pixel: gamma and black level, then defocus.
    const ProjectorOptics& optics = rig_.projector_optics;
    float lut[256];
    for (int level = 0; level < 256; ++level)
        lut[level] = static_cast<float>(std::pow(level / 255.0, optics.gamma) + optics.black_level);
    const int PW = rig_.projector_size.width, PH = rig_.projector_size.height;
    light.resize(rig_.projector_size.area());
    {
        const std::uint8_t* src = projector_image.data();
        float* dst = light.data();
        const std::size_t n = light.size();
        for (std::size_t k = 0; k < n; ++k)
            dst[k] = lut[src[k]];
    }
    detail::gaussian_blur(light.data(), PW, PH, optics.defocus_sigma_px, detail::Border::zero,
                          *pool_, blur);

    const int W = rig_.camera_size.width, H = rig_.camera_size.height;
    radiance.resize(rig_.camera_size.area());
    const float* L = light.data();
    pool_->parallel_for(H, row_grain(H, *pool_), [&](int y0, int y1, int) {
        for (int y = y0; y < y1; ++y) {
            const std::size_t base = static_cast<std::size_t>(y) * W;
            const float* gain = radiance_gain_.row(y);
            const float* amb = ambient_.row(y);
            const std::uint32_t* idx = sample_index_.data() + base;
            const float* fx = sample_fx_.data() + base;
            const float* fy = sample_fy_.data() + base;
            float* out = radiance.data() + base;
            for (int x = 0; x < W; ++x) {
                const float* p = L + idx[x];
                const float top = p[0] + fx[x] * (p[1] - p[0]);
                const float bottom = p[PW] + fx[x] * (p[PW + 1] - p[PW]);
                out[x] = gain[x] * (top + fy[x] * (bottom - top)) + amb[x];
            }
        }
    });
    detail::gaussian_blur(radiance.data(), W, H, rig_.sensor.defocus_sigma_px,
                          detail::Border::clamp, *pool_, blur);
}

Image<float> Renderer::render_radiance(const Image<std::uint8_t>& projector_image) const {
    std::vector<float> radiance, light, blur;
    radiance_into(projector_image, radiance, light, blur);
    Image<float> out(rig_.camera_size);
    std::copy(radiance.begin(), radiance.end(), out.data());
    return out;
}

Frame Renderer::render(const Image<std::uint8_t>& projector_image, std::uint64_t noise_seed,
                       double exposure_scale) const {
    Scratch& scratch = thread_scratch();
    radiance_into(projector_image, scratch.radiance, scratch.light, scratch.blur);
    const std::vector<float>& radiance = scratch.radiance;
    const SensorModel& sensor = rig_.sensor;
    const int W = rig_.camera_size.width, H = rig_.camera_size.height;
    const float full = static_cast<float>(rig_.full_scale_dn());
    const int shift = sensor.bit_depth > 8 ? 16 - sensor.bit_depth : 0;
    const bool noisy = sensor.read_noise_dn > 0 || sensor.gain_e_per_dn > 0;
    const float read_var = static_cast<float>(sensor.read_noise_dn * sensor.read_noise_dn);
    // Shot noise: N electrons = DN * gain has variance N, i.e. DN / gain in DN^2.
    const float shot_per_dn =
        sensor.gain_e_per_dn > 0 ? static_cast<float>(1 / sensor.gain_e_per_dn) : 0.0f;
    const std::uint64_t key = detail::mix64(noise_seed ^ 0x6a09e667f3bcc909ULL);
    static const detail::NormalTable normal;

    Frame frame;
    frame.bit_depth = sensor.bit_depth > 8 ? 16 : 8;
    if (frame.bit_depth == 8)
        frame.u8 = Image<std::uint8_t>(W, H);
    else
        frame.u16 = Image<std::uint16_t>(W, H);

    scratch.noisy_rows.resize(static_cast<std::size_t>(pool_->size()) *
                              static_cast<std::size_t>(W));
    pool_->parallel_for(H, row_grain(H, *pool_), [&](int y0, int y1, int worker) {
        // Local copies: seen through the closure, the captures could alias
        // the 8-bit output rows, and every store would reload them (no
        // vectorisation).
        const int width = W;
        const float full_dn = full;
        const int msb_shift = shift;
        const float noise_read_var = read_var, noise_shot_per_dn = shot_per_dn;
        const float scale = static_cast<float>(exposure_scale);
        float* v = scratch.noisy_rows.data() +
                   static_cast<std::size_t>(worker) * static_cast<std::size_t>(width);
        for (int y = y0; y < y1; ++y) {
            const std::size_t first = static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
            const float* in = radiance.data() + first;
            if (noisy) {
                for (int x = 0; x < width; ++x)
                    v[x] = normal(key, first + static_cast<std::size_t>(x));
                // Signal-dependent sigma, in a separate loop that vectorises.
                for (int x = 0; x < width; ++x) {
                    const float signal = scale * in[x];
                    v[x] = signal +
                           std::sqrt(noise_read_var + noise_shot_per_dn * std::max(signal, 0.0f)) *
                               v[x];
                }
            } else {
                for (int x = 0; x < width; ++x)
                    v[x] = scale * in[x];
            }
            // Round to the nearest DN, clip to [0, full scale] (saturation).
            if (frame.bit_depth == 8) {
                std::uint8_t* out = frame.u8.row(y);
                for (int x = 0; x < width; ++x)
                    out[x] = static_cast<std::uint8_t>(std::clamp(v[x], 0.0f, full_dn) + 0.5f);
            } else {
                std::uint16_t* out = frame.u16.row(y);
                for (int x = 0; x < width; ++x)
                    out[x] = static_cast<std::uint16_t>(
                        static_cast<std::uint32_t>(std::clamp(v[x], 0.0f, full_dn) + 0.5f)
                        << msb_shift);
            }
        }
    });
    return frame;
}

} // namespace fpp::sim
