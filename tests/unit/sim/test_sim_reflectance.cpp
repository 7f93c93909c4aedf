// Reflectance in the virtual scanner: the specular lobe's highlight where the
// surface normal is the half vector of the projector and camera directions,
// the lobe lit by the projector pixel like the diffuse term, bit-identical
// renders without a lobe, per-object truth labels, and the HDR scene
// "hdr-parts" (white part near 200 DN, dark part a few DN, highlight clipping
// at the nominal exposure and not at 1/8 of it).

#include "fpp/simulator/renderer.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace {

using fpp::Frame;
using fpp::Image;
using fpp::Size;
using fpp::Vec2;
using fpp::Vec3;
using namespace fpp::sim;

using fpp::vec::add;
using fpp::vec::dot;
using fpp::vec::normalised;
using fpp::vec::scale;
using fpp::vec::sub;

Image<std::uint8_t> uniform(Size size, int level) {
    return Image<std::uint8_t>(size, 1, static_cast<std::uint8_t>(level));
}

// The paper's rig with every effect off, 4 x 4 binned (400 x 300).
Rig small_rig() {
    return Rig::paper().without_effects().binned_camera(4);
}

// Brightest pixel of a radiance image.
struct Peak {
    int x = 0, y = 0;
    double value = 0;
};
Peak brightest(const Image<float>& image) {
    Peak p;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x)
            if (double(image.at(x, y)) > p.value)
                p = {x, y, double(image.at(x, y))};
    return p;
}

// The point of the sphere (centre c, radius r) whose outward normal is the
// half vector of the directions to the projector centre and to the camera
// centre (the mirror point of the projector centre seen from the camera).
Vec3 mirror_point(const Vec3& c, double r, const Vec3& projector) {
    Vec3 n = normalised(scale(c, -1.0));
    for (int i = 0; i < 200; ++i) {
        const Vec3 p = add(c, scale(n, r));
        n = normalised(add(normalised(sub(projector, p)), normalised(scale(p, -1.0))));
    }
    return add(c, scale(n, r));
}

TEST(SimReflectance, HighlightSitsWhereTheSphereNormalIsTheHalfVector) {
    const Rig rig = small_rig();
    const Vec3 centre{10, -5, 480};
    const double radius = 60, albedo = 0.3;
    const SpecularLobe lobe{0.5, 400};
    Scene glossy, matte;
    glossy.add(std::make_unique<Sphere>(centre, radius, albedo), "ball", lobe);
    matte.add(std::make_unique<Sphere>(centre, radius, albedo), "ball");
    const Renderer rg(rig, glossy, 2), rm(rig, matte, 2);
    const Image<float> white_g = rg.render_radiance(uniform(rig.projector_size, 255));
    const Image<float> white_m = rm.render_radiance(uniform(rig.projector_size, 255));

    const Vec3 projector = rig.projector_centre_in_camera();
    const Vec3 p = mirror_point(centre, radius, projector);
    const Vec2 expected = rig.camera.project(p);
    const Peak got = brightest(white_g);
    const double off = std::hypot(got.x - expected[0], got.y - expected[1]);
    // The matte sphere is brightest where it faces the projector, elsewhere.
    const Peak diffuse = brightest(white_m);
    const double diffuse_off = std::hypot(diffuse.x - expected[0], diffuse.y - expected[1]);
    // Peak radiance: white level x cos(incidence) x (albedo + ks (n + 8) / 8) at the mirror point.
    const Vec3 normal = normalised(sub(p, centre));
    const double cos_inc = dot(normal, normalised(sub(projector, p)));
    const double peak =
        rig.sensor.white_level * cos_inc * (albedo + lobe.specular * (lobe.shininess + 8) / 8);
    std::printf("highlight: brightest pixel (%d, %d), mirror point projects to (%.2f, %.2f): "
                "%.2f px apart (matte sphere's brightest: %.1f px away); peak %.1f DN, analytic "
                "%.1f DN (%.2f x the matte peak)\n",
                got.x, got.y, expected[0], expected[1], off, diffuse_off, got.value, peak,
                got.value / diffuse.value);
    EXPECT_LE(off, 1.5);
    EXPECT_GT(diffuse_off, 10.0);
    EXPECT_NEAR(got.value, peak, 0.02 * peak);
    // Away from the lobe the glossy sphere is the matte one.
    EXPECT_EQ(white_g.at(got.x - 60, got.y), white_m.at(got.x - 60, got.y));
    // The lobe is an addition: never darker than the matte sphere.
    for (std::size_t i = 0; i < white_g.pixel_count(); ++i)
        ASSERT_GE(white_g.data()[i], white_m.data()[i]);
}

TEST(SimReflectance, SpecularLightFollowsTheProjectorPixelLikeTheDiffuseLight) {
    // The lobe scales the light of the projector pixel that lights the point:
    // glossy / matte radiance is the same under any pattern, so the fringe
    // phase is unchanged and only the dynamic range grows.
    const Rig rig = small_rig();
    Scene glossy, matte;
    glossy.add(std::make_unique<Cylinder>(Vec3{0, 0, 480}, Vec3{0, 1, 0}, 50, 200, 0.2), "metal",
               SpecularLobe{0.6, 60});
    matte.add(std::make_unique<Cylinder>(Vec3{0, 0, 480}, Vec3{0, 1, 0}, 50, 200, 0.2), "metal");
    const Renderer rg(rig, glossy, 2), rm(rig, matte, 2);
    Image<std::uint8_t> fringes(rig.projector_size);
    for (int y = 0; y < fringes.height(); ++y)
        for (int x = 0; x < fringes.width(); ++x)
            fringes.at(x, y) = static_cast<std::uint8_t>(
                std::lround(127.5 + 127.5 * std::cos(2 * 3.14159265358979 * x / 37.0)));
    const Image<float> wg = rg.render_radiance(uniform(rig.projector_size, 255));
    const Image<float> wm = rm.render_radiance(uniform(rig.projector_size, 255));
    const Image<float> fg = rg.render_radiance(fringes);
    const Image<float> fm = rm.render_radiance(fringes);
    double worst = 0, max_gain = 0;
    long checked = 0;
    for (std::size_t i = 0; i < wg.pixel_count(); ++i) {
        if (!(wm.data()[i] > 1) || !(fm.data()[i] > 1))
            continue;
        const double gain = double(wg.data()[i]) / double(wm.data()[i]);
        max_gain = std::max(max_gain, gain);
        worst = std::max(worst, std::fabs(double(fg.data()[i]) / double(fm.data()[i]) / gain - 1));
        ++checked;
    }
    std::printf("lobe under fringes: %ld pixels, glossy / matte up to %.1f, same ratio as under "
                "white to %.2g\n",
                checked, max_gain, worst);
    EXPECT_GT(checked, 20000);
    EXPECT_GT(max_gain, 10.0);
    EXPECT_LT(worst, 1e-5);
}

bool same_frames(const Frame& a, const Frame& b) {
    return a.bit_depth == b.bit_depth && a.u8.storage() == b.u8.storage() &&
           a.u16.storage() == b.u16.storage();
}

bool same_floats(const Image<float>& a, const Image<float>& b) {
    return a.size() == b.size() && a.storage().size() == b.storage().size() &&
           std::memcmp(a.data(), b.data(), a.storage().size() * sizeof(float)) == 0;
}

TEST(SimReflectance, ZeroSpecularRendersBitIdenticallyToNoMaterial) {
    // The effects rig (noise, ambient, falloff, blur) on the composite, its
    // shapes once as they are and once with a lobe of strength 0, from YAML.
    fpp::test::TempDir dir;
    const auto plain = dir / "plain.yaml", zero = dir / "zero.yaml";
    std::ofstream(plain) << R"(format: fpp-scene/1
shapes:
  - {type: plane, centre: [0, 0, 540], size: [420, 330], albedo: 0.85}
  - {type: relief, centre: [-45, 5, 505], size: [160, 220], albedo: 0.8}
  - {type: sphere, centre: [80, 25, 450], radius: 38, albedo: 0.9}
)";
    std::ofstream(zero) << R"(format: fpp-scene/1
shapes:
  - {type: plane, centre: [0, 0, 540], size: [420, 330], material: {albedo: 0.85, specular: 0}}
  - {type: relief, centre: [-45, 5, 505], size: [160, 220],
     material: {albedo: 0.8, specular: 0, shininess: 50}}
  - {type: sphere, centre: [80, 25, 450], radius: 38,
     material: {albedo: 0.9, specular: 0, roughness: 0.1}}
)";
    const Rig rig = load_rig(effects_rig_path()).binned_camera(4);
    const Renderer a(rig, load_scene(plain), 2), b(rig, load_scene(zero), 2),
        builtin(rig, named_scene("composite"), 2);
    Image<std::uint8_t> pattern(rig.projector_size);
    for (int y = 0; y < pattern.height(); ++y)
        for (int x = 0; x < pattern.width(); ++x)
            pattern.at(x, y) = static_cast<std::uint8_t>((x * 7 + y * 3) % 256);
    EXPECT_TRUE(same_frames(a.render(pattern, 5), b.render(pattern, 5)));
    EXPECT_TRUE(same_frames(a.render(pattern, 5), builtin.render(pattern, 5)));
    EXPECT_TRUE(same_frames(a.render(pattern, 6, 0.25), b.render(pattern, 6, 0.25)));
    EXPECT_TRUE(same_floats(a.render_radiance(pattern), b.render_radiance(pattern)));
    EXPECT_TRUE(same_floats(a.truth_xyz(), b.truth_xyz()));
    EXPECT_TRUE(same_floats(a.albedo(), b.albedo()));
    EXPECT_EQ(a.truth_object().storage(), b.truth_object().storage());
    // A lobe, however weak, changes the render: the comparison can fail.
    Scene weak;
    weak.add(
        std::make_unique<Plane>(Pose{{0, 0, 540}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 420, 330, 0.85));
    weak.add(std::make_unique<Relief>(Pose{{-45, 5, 505}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 160, 220,
                                      Relief::face_bumps(), 0.8));
    weak.add(std::make_unique<Sphere>(Vec3{80, 25, 450}, 38, 0.9), "", SpecularLobe{0.01, 10});
    const Renderer c(rig, weak, 2);
    EXPECT_FALSE(same_floats(a.render_radiance(pattern), c.render_radiance(pattern)));
}

TEST(SimReflectance, TruthObjectLabelsEachPixelWithTheObjectItSees) {
    const Rig rig = small_rig();
    const Renderer r(rig, named_scene("hdr-parts"), 2);
    const Image<std::int32_t>& objects = r.truth_object();
    ASSERT_EQ(objects.size(), rig.camera_size);
    ASSERT_EQ(objects.channels(), 1);
    ASSERT_EQ(r.object_count(), 4u);
    std::map<std::string, long> pixels;
    double worst = 0; // distance of a labelled point from its object's surface, mm
    long shadowed = 0;
    for (int y = 0; y < objects.height(); ++y)
        for (int x = 0; x < objects.width(); ++x) {
            const std::int32_t k = objects.at(x, y);
            const Vec3 p{r.truth_xyz().at(x, y, 0), r.truth_xyz().at(x, y, 1),
                         r.truth_xyz().at(x, y, 2)};
            ASSERT_EQ(k == Renderer::kNoObject, std::isnan(p[2])) << x << ", " << y;
            const std::string& name = r.object_name(k);
            ++pixels[name];
            shadowed += k != Renderer::kNoObject && std::isnan(r.truth_projector().at(x, y, 0));
            double e = 0;
            if (name == "background") {
                e = std::fabs(p[2] - 540);
            } else if (name == "white") {
                e = std::fabs(std::sqrt(dot(sub(p, {-70, -42, 480}), sub(p, {-70, -42, 480}))) -
                              36);
            } else if (name == "metal") {
                e = std::fabs(std::hypot(p[0] - 72, p[2] - 470) - 28);
            } else if (name == "dark") {
                // On the pad (|x| <= 62, |y| <= 42 about its centre), in front of the plate.
                e = std::max(
                    {std::fabs(p[0] + 62) - 62, std::fabs(p[1] - 55) - 42, p[2] - 505, 0.0});
                EXPECT_GE(p[2], 505 - 24 - 1e-3);
            } else {
                EXPECT_EQ(name, "none");
            }
            worst = std::max(worst, e);
        }
    std::printf("truth_object:");
    for (const auto& [name, n] : pixels)
        std::printf(" %s %ld,", name.c_str(), n);
    std::printf(" %ld labelled pixels in projector shadow; worst distance to the labelled "
                "surface %.2g mm\n",
                shadowed, worst);
    // float truth (camera frame, ~500 mm): ~3e-5 mm of rounding.
    EXPECT_LT(worst, 1e-3);
    for (const char* part : {"background", "white", "dark", "metal"})
        EXPECT_GT(pixels[part], 5000) << part;
    EXPECT_GT(shadowed, 1000); // labels cover shadows too
    EXPECT_EQ(r.object_name(Renderer::kNoObject), "none");
    EXPECT_THROW(r.object_name(4), std::out_of_range);
    EXPECT_THROW(r.object_name(-2), std::out_of_range);
    // Unnamed objects are "object<i>".
    Scene s;
    s.add(std::make_unique<Sphere>(Vec3{0, 0, 480}, 60, 0.9));
    EXPECT_EQ(s.object_name(0), "object0");
}

// DN figures of one part over the pixels where the projector lights it.
struct PartDn {
    std::vector<int> dn;
    long clipped = 0;
    int quantile(double q) const {
        std::vector<int> v = dn;
        std::sort(v.begin(), v.end());
        return v.empty() ? -1 : v[static_cast<std::size_t>(q * double(v.size() - 1))];
    }
};

std::map<std::string, PartDn> parts_dn(const Renderer& r, const Frame& frame) {
    std::map<std::string, PartDn> parts;
    const float* lit = r.truth_projector().data();
    const std::int32_t* objects = r.truth_object().data();
    for (std::size_t i = 0; i < frame.u8.pixel_count(); ++i) {
        if (objects[i] == Renderer::kNoObject || std::isnan(lit[2 * i]))
            continue;
        PartDn& part = parts[r.object_name(objects[i])];
        part.dn.push_back(frame.u8.data()[i]);
        part.clipped += frame.u8.data()[i] == 255;
    }
    return parts;
}

TEST(SimReflectance, HdrPartsExposeWhiteNear200DarkAtAFewDnAndClipTheHighlight) {
    for (const bool effects : {false, true}) {
        const Rig rig = (effects ? load_rig(effects_rig_path()) : load_rig(default_rig_path()))
                            .binned_camera(4);
        ASSERT_EQ(rig.sensor.bit_depth, 8);
        const Renderer r(rig, named_scene("hdr-parts"), 2);
        const auto white = uniform(rig.projector_size, 255);
        auto nominal = parts_dn(r, r.render(white, 11, 1.0));
        auto eighth = parts_dn(r, r.render(white, 12, 0.125));
        const double peak = brightest(r.render_radiance(white)).value;
        const PartDn &w = nominal["white"], &d = nominal["dark"], &m = nominal["metal"];
        std::printf("hdr-parts on the %s rig, nominal exposure: white p50 %d p99 %d DN (%ld "
                    "clipped), dark p50 %d p95 %d DN, metal p50 %d DN, highlight peak %.0f DN, "
                    "%ld metal pixels clipped; at 1/8: white p99 %d, %ld metal pixels clipped\n",
                    effects ? "effects" : "paper", w.quantile(0.5), w.quantile(0.99), w.clipped,
                    d.quantile(0.5), d.quantile(0.95), m.quantile(0.5), peak, m.clipped,
                    eighth["white"].quantile(0.99), eighth["metal"].clipped);
        ASSERT_GT(w.dn.size(), 5000u);
        ASSERT_GT(d.dn.size(), 5000u);
        ASSERT_GT(m.dn.size(), 5000u);
        // The exposure that suits the white part: its brightest near 200 of 255 DN, none clipped.
        EXPECT_GE(w.quantile(0.99), 180);
        EXPECT_LE(w.quantile(0.99), 230);
        EXPECT_EQ(w.clipped, 0);
        EXPECT_EQ(nominal["background"].clipped, 0);
        // The dark part: a few DN.
        EXPECT_GE(d.quantile(0.5), 2);
        EXPECT_LE(d.quantile(0.95), 10);
        // The highlight clips over a visible area (>= 1000 of 400 x 300 pixels)...
        EXPECT_GE(m.clipped, 1000);
        EXPECT_GT(peak, 6 * 255.0); // several times full scale
        // ...and at 1/8 of the exposure no longer over most of it.
        EXPECT_LE(eighth["metal"].clipped, m.clipped / 10);
    }
}

TEST(SimReflectance, HdrPartsFileIsTheBuiltInScene) {
    const auto path = fpp::test::source_dir() / "board/sim/scenes/hdr-parts.yaml";
    const Scene file = load_scene(path);
    const Scene builtin = named_scene("hdr-parts");
    ASSERT_EQ(file.size(), builtin.size());
    for (std::size_t i = 0; i < file.size(); ++i) {
        EXPECT_EQ(file.object_name(i), builtin.object_name(i));
        EXPECT_EQ(file.specular(i).specular, builtin.specular(i).specular);
        EXPECT_EQ(file.specular(i).shininess, builtin.specular(i).shininess);
    }
    EXPECT_TRUE(builtin.specular(3).active());
    int checked = 0;
    for (double y = -0.22; y <= 0.22; y += 0.011)
        for (double x = -0.29; x <= 0.29; x += 0.013) {
            Hit a, b;
            const Vec3 d = normalised({x, y, 1});
            ASSERT_EQ(file.intersect({0, 0, 0}, d, a), builtin.intersect({0, 0, 0}, d, b));
            EXPECT_EQ(a.object, b.object);
            EXPECT_EQ(a.t, b.t);
            EXPECT_EQ(a.albedo, b.albedo);
            ++checked;
        }
    EXPECT_GT(checked, 1500);
}

} // namespace
