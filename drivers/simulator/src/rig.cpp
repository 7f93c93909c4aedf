#include "fpp/simulator/rig.hpp"

#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"
#include "yaml_emit.hpp"

#include <cmath>
#include <initializer_list>
#include <utility>

namespace fpp::sim {

using yaml_fields::child;
using yaml_fields::item;
using yaml_fields::Reader;

namespace {

constexpr const char* kRigFormat = "fpp-rig/1";

// ---- reading -------------------------------------------------------------

void read_lens(const Reader& in, const YAML::Node& node, const std::string& field, Size& size,
               LensModel& lens) {
    in.expect_map(node, field,
                  {"width", "height", "focal_px", "principal_px", "skew", "distortion",
                   "unmodelled_distortion"});
    size.width = in.int_value(in.require(node, field, "width"), child(field, "width"));
    size.height = in.int_value(in.require(node, field, "height"), child(field, "height"));
    const auto f = in.real_array<2>(in.require(node, field, "focal_px"), child(field, "focal_px"));
    const auto c =
        in.real_array<2>(in.require(node, field, "principal_px"), child(field, "principal_px"));
    lens.fu = f[0];
    lens.fv = f[1];
    lens.cu = c[0];
    lens.cv = c[1];
    lens.skew = in.real_value(in.require(node, field, "skew"), child(field, "skew"));

    const std::string dfield = child(field, "distortion");
    const YAML::Node d = in.require(node, field, "distortion");
    in.expect_map(d, dfield, {"k1", "k2", "k3", "p1", "p2"});
    lens.k1 = in.real_value(in.require(d, dfield, "k1"), child(dfield, "k1"));
    lens.k2 = in.real_value(in.require(d, dfield, "k2"), child(dfield, "k2"));
    lens.k3 = in.real_value(in.require(d, dfield, "k3"), child(dfield, "k3"));
    lens.p1 = in.real_value(in.require(d, dfield, "p1"), child(dfield, "p1"));
    lens.p2 = in.real_value(in.require(d, dfield, "p2"), child(dfield, "p2"));

    const YAML::Node u = node["unmodelled_distortion"];
    if (u.IsDefined()) {
        const std::string ufield = child(field, "unmodelled_distortion");
        in.expect_map(u, ufield,
                      {"k4", "s1", "s2", "s3", "s4", "t1", "t2", "dc_k1", "dc_k2", "dc_x", "dc_y"});
        lens.k4 = in.real_value_or(u, ufield, "k4", 0);
        lens.s1 = in.real_value_or(u, ufield, "s1", 0);
        lens.s2 = in.real_value_or(u, ufield, "s2", 0);
        lens.s3 = in.real_value_or(u, ufield, "s3", 0);
        lens.s4 = in.real_value_or(u, ufield, "s4", 0);
        lens.t1 = in.real_value_or(u, ufield, "t1", 0);
        lens.t2 = in.real_value_or(u, ufield, "t2", 0);
        lens.dc_k1 = in.real_value_or(u, ufield, "dc_k1", 0);
        lens.dc_k2 = in.real_value_or(u, ufield, "dc_k2", 0);
        lens.dc_x = in.real_value_or(u, ufield, "dc_x", 0);
        lens.dc_y = in.real_value_or(u, ufield, "dc_y", 0);
    }
}

Mat3 read_rotation(const Reader& in, const YAML::Node& ext) {
    const YAML::Node euler = ext["euler_deg"];
    const YAML::Node matrix = ext["rotation"];
    if (euler.IsDefined() == matrix.IsDefined())
        in.fail(ext, "extrinsics", "give exactly one of euler_deg and rotation");
    if (euler.IsDefined()) {
        const auto e = in.real_array<3>(euler, "extrinsics.euler_deg");
        return rotation_from_euler_deg(e[0], e[1], e[2]);
    }
    const std::string field = "extrinsics.rotation";
    if (!matrix.IsSequence() || matrix.size() != 3)
        in.fail(matrix, field, "expected a 3x3 matrix (three rows of three numbers)");
    Mat3 R{};
    for (std::size_t i = 0; i < 3; ++i) {
        const auto row = in.real_array<3>(matrix[i], item(field, i));
        for (std::size_t j = 0; j < 3; ++j)
            R[i * 3 + j] = row[j];
    }
    // Must be a proper rotation: R R^T = I, det = +1 (to 1e-6, i.e. printed to 7 digits).
    const Mat3 RRt = mul(R, transpose(R));
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (std::fabs(RRt[i * 3 + j] - (i == j ? 1.0 : 0.0)) > 1e-6)
                in.fail(matrix, field, "not orthonormal (R R^T != I)");
    const double det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                       R[2] * (R[3] * R[7] - R[4] * R[6]);
    if (det < 0)
        in.fail(matrix, field, "determinant is -1 (a reflection)");
    return R;
}

// ---- writing -------------------------------------------------------------

void write_lens(YAML::Emitter& out, const char* name, Size size, const LensModel& l) {
    using yaml_emit::real;
    out << YAML::Key << name << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "width" << YAML::Value << size.width;
    out << YAML::Key << "height" << YAML::Value << size.height;
    out << YAML::Key << "focal_px" << YAML::Value;
    yaml_emit::flow_reals(out, {l.fu, l.fv});
    out << YAML::Key << "principal_px" << YAML::Value;
    yaml_emit::flow_reals(out, {l.cu, l.cv});
    out << YAML::Key << "skew" << YAML::Value;
    real(out, l.skew);
    auto flow_map = [&](const char* key,
                        std::initializer_list<std::pair<const char*, double>> terms) {
        out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap;
        for (const auto& [term, value] : terms) {
            out << YAML::Key << term << YAML::Value;
            real(out, value);
        }
        out << YAML::EndMap;
    };
    flow_map("distortion", {{"k1", l.k1}, {"k2", l.k2}, {"k3", l.k3}, {"p1", l.p1}, {"p2", l.p2}});
    // Also when only the decentred element's centre is set, so that it survives a round trip.
    if (l.has_unmodelled_terms() || l.dc_x != 0 || l.dc_y != 0)
        flow_map("unmodelled_distortion", {{"k4", l.k4},
                                           {"s1", l.s1},
                                           {"s2", l.s2},
                                           {"s3", l.s3},
                                           {"s4", l.s4},
                                           {"t1", l.t1},
                                           {"t2", l.t2},
                                           {"dc_k1", l.dc_k1},
                                           {"dc_k2", l.dc_k2},
                                           {"dc_x", l.dc_x},
                                           {"dc_y", l.dc_y}});
    out << YAML::EndMap;
}

void check_lens(const std::filesystem::path& origin, const std::string& field, Size size,
                const LensModel& l) {
    if (size.width < 2 || size.height < 2 || size.width > 65536 || size.height > 65536)
        throw InputError(origin, field + ".width", "image size must be 2..65536 pixels per side");
    const double all[] = {l.fu, l.fv, l.cu, l.cv,    l.skew,  l.k1,   l.k2,
                          l.k3, l.p1, l.p2, l.k4,    l.s1,    l.s2,   l.s3,
                          l.s4, l.t1, l.t2, l.dc_k1, l.dc_k2, l.dc_x, l.dc_y};
    for (double v : all)
        if (!std::isfinite(v))
            throw InputError(origin, field, "non-finite lens parameter");
    if (!(l.fu > 0) || !(l.fv > 0))
        throw InputError(origin, field + ".focal_px", "focal lengths must be positive");
}

} // namespace

Rig Rig::paper() {
    Rig rig;
    rig.name = "paper-rig";
    rig.camera_size = {1600, 1200};
    rig.projector_size = {1280, 800};
    rig.camera.fu = 2698.42;
    rig.camera.fv = 2701.55;
    rig.camera.cu = 794.59;
    rig.camera.cv = 594.32;
    rig.camera.skew = 0.84;
    rig.camera.k1 = -0.12;
    rig.camera.k2 = -0.52;
    rig.camera.k3 = 5.08;
    rig.camera.p1 = 0.0011;
    rig.camera.p2 = 0.0006;
    rig.projector.fu = 1949.18;
    rig.projector.fv = 1953.15;
    rig.projector.cu = 632.42;
    rig.projector.cv = 799.67;
    rig.projector.skew = 0.83;
    rig.projector.k1 = 0.002;
    rig.projector.k2 = -0.077;
    rig.projector.k3 = -0.033;
    rig.projector.p1 = 0.0004;
    rig.projector.p2 = 0.0002;
    rig.R = rotation_from_euler_deg(-0.42, 19.08, 0.36);
    rig.t = {-163.71, -116.73, 135.41};
    // White on albedo 0.9 at the 480 mm plane (projector incidence ~23 deg) is ~200 DN.
    rig.sensor.bit_depth = 8;
    rig.sensor.white_level = 240;
    return rig;
}

Vec3 Rig::projector_centre_in_camera() const {
    const Vec3 c = mul(transpose(R), t);
    return {-c[0], -c[1], -c[2]};
}

Rig Rig::without_effects() const {
    Rig r = *this;
    r.camera.drop_unmodelled_terms();
    r.projector.drop_unmodelled_terms();
    r.sensor.ambient = 0;
    r.sensor.read_noise_dn = 0;
    r.sensor.gain_e_per_dn = 0;
    r.sensor.defocus_sigma_px = 0;
    r.sensor.reference_distance_mm = 0;
    r.projector_optics = ProjectorOptics{};
    return r;
}

Rig Rig::binned_camera(int factor) const {
    if (factor < 1)
        throw std::invalid_argument("binned_camera: factor must be >= 1");
    Rig r = *this;
    const double k = factor;
    r.camera_size = {camera_size.width / factor, camera_size.height / factor};
    r.camera.fu /= k;
    r.camera.fv /= k;
    r.camera.skew /= k;
    r.camera.cu = (camera.cu + 0.5) / k - 0.5;
    r.camera.cv = (camera.cv + 0.5) / k - 0.5;
    r.sensor.defocus_sigma_px /= k;
    return r;
}

double Rig::full_scale_dn() const {
    return std::ldexp(1.0, sensor.bit_depth) - 1.0;
}

void Rig::validate(const std::filesystem::path& origin) const {
    check_lens(origin, "camera", camera_size, camera);
    check_lens(origin, "projector", projector_size, projector);
    for (double v : R)
        if (!std::isfinite(v))
            throw InputError(origin, "extrinsics.rotation", "non-finite");
    for (double v : t)
        if (!std::isfinite(v))
            throw InputError(origin, "extrinsics.translation_mm", "non-finite");
    const SensorModel& s = sensor;
    if (s.bit_depth != 8 && s.bit_depth != 10 && s.bit_depth != 12 && s.bit_depth != 16)
        throw InputError(origin, "sensor.bit_depth", "must be 8, 10, 12 or 16");
    if (!(s.white_level > 0) || !std::isfinite(s.white_level))
        throw InputError(origin, "sensor.white_level", "must be a positive number of DN");
    auto non_negative = [&](double v, const char* field) {
        if (!(v >= 0) || !std::isfinite(v))
            throw InputError(origin, field, "must be a finite number >= 0");
    };
    non_negative(s.ambient, "sensor.ambient");
    non_negative(s.read_noise_dn, "sensor.read_noise_dn");
    non_negative(s.gain_e_per_dn, "sensor.gain_e_per_dn");
    non_negative(s.defocus_sigma_px, "sensor.defocus_sigma_px");
    non_negative(s.reference_distance_mm, "sensor.reference_distance_mm");
    if (s.defocus_sigma_px > 20)
        throw InputError(origin, "sensor.defocus_sigma_px", "must be <= 20");
    const ProjectorOptics& p = projector_optics;
    if (!(p.gamma > 0.1 && p.gamma < 10))
        throw InputError(origin, "projector_optics.gamma", "must be in (0.1, 10)");
    if (!(p.black_level >= 0 && p.black_level < 1))
        throw InputError(origin, "projector_optics.black_level", "must be in [0, 1)");
    non_negative(p.defocus_sigma_px, "projector_optics.defocus_sigma_px");
    if (p.defocus_sigma_px > 20)
        throw InputError(origin, "projector_optics.defocus_sigma_px", "must be <= 20");
}

Rig load_rig(const std::filesystem::path& path) {
    const Reader in(path);
    const YAML::Node root = in.load_file();
    if (!root.IsMap())
        in.fail(root, "(top level)", std::string("expected a map with format: ") + kRigFormat);
    in.expect_map(
        root, "",
        {"format", "name", "camera", "projector", "extrinsics", "sensor", "projector_optics"});
    const YAML::Node format_node = in.require(root, "", "format");
    const std::string format = in.string_value(format_node, "format");
    if (format != kRigFormat)
        in.fail(format_node, "format",
                "unknown format '" + format + "' (expected " + kRigFormat + ")");

    Rig rig;
    rig.name =
        root["name"].IsDefined() ? in.string_value(root["name"], "name") : path.stem().string();
    read_lens(in, in.require(root, "", "camera"), "camera", rig.camera_size, rig.camera);
    read_lens(in, in.require(root, "", "projector"), "projector", rig.projector_size,
              rig.projector);

    const YAML::Node ext = in.require(root, "", "extrinsics");
    in.expect_map(ext, "extrinsics", {"euler_deg", "rotation", "translation_mm"});
    rig.R = read_rotation(in, ext);
    rig.t = in.real_array<3>(in.require(ext, "extrinsics", "translation_mm"),
                             "extrinsics.translation_mm");

    const YAML::Node sensor = in.require(root, "", "sensor");
    in.expect_map(sensor, "sensor",
                  {"bit_depth", "white_level", "ambient", "read_noise_dn", "gain_e_per_dn",
                   "defocus_sigma_px", "reference_distance_mm"});
    rig.sensor.bit_depth =
        in.int_value(in.require(sensor, "sensor", "bit_depth"), "sensor.bit_depth");
    rig.sensor.white_level =
        in.real_value(in.require(sensor, "sensor", "white_level"), "sensor.white_level");
    rig.sensor.ambient = in.real_value_or(sensor, "sensor", "ambient", 0);
    rig.sensor.read_noise_dn = in.real_value_or(sensor, "sensor", "read_noise_dn", 0);
    rig.sensor.gain_e_per_dn = in.real_value_or(sensor, "sensor", "gain_e_per_dn", 0);
    rig.sensor.defocus_sigma_px = in.real_value_or(sensor, "sensor", "defocus_sigma_px", 0);
    rig.sensor.reference_distance_mm =
        in.real_value_or(sensor, "sensor", "reference_distance_mm", 0);

    const YAML::Node optics = root["projector_optics"];
    if (optics.IsDefined()) {
        in.expect_map(optics, "projector_optics", {"gamma", "black_level", "defocus_sigma_px"});
        rig.projector_optics.gamma = in.real_value_or(optics, "projector_optics", "gamma", 1);
        rig.projector_optics.black_level =
            in.real_value_or(optics, "projector_optics", "black_level", 0);
        rig.projector_optics.defocus_sigma_px =
            in.real_value_or(optics, "projector_optics", "defocus_sigma_px", 0);
    }
    rig.validate(path);
    return rig;
}

std::string rig_to_yaml(const Rig& rig) {
    using yaml_emit::real;
    YAML::Emitter out;
    out << YAML::BeginMap;
    out << YAML::Key << "format" << YAML::Value << kRigFormat;
    out << YAML::Key << "name" << YAML::Value << rig.name;
    write_lens(out, "camera", rig.camera_size, rig.camera);
    write_lens(out, "projector", rig.projector_size, rig.projector);

    out << YAML::Key << "extrinsics" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "rotation" << YAML::Value << YAML::BeginSeq;
    for (std::size_t row = 0; row < 3; ++row)
        yaml_emit::flow_reals(out, rig.R.data() + 3 * row, 3);
    out << YAML::EndSeq;
    out << YAML::Key << "translation_mm" << YAML::Value;
    yaml_emit::flow_reals(out, rig.t.data(), 3);
    out << YAML::EndMap;

    const SensorModel& s = rig.sensor;
    out << YAML::Key << "sensor" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "bit_depth" << YAML::Value << s.bit_depth;
    const std::pair<const char*, double> sensor_reals[] = {
        {"white_level", s.white_level},
        {"ambient", s.ambient},
        {"read_noise_dn", s.read_noise_dn},
        {"gain_e_per_dn", s.gain_e_per_dn},
        {"defocus_sigma_px", s.defocus_sigma_px},
        {"reference_distance_mm", s.reference_distance_mm}};
    for (const auto& [key, value] : sensor_reals) {
        out << YAML::Key << key << YAML::Value;
        real(out, value);
    }
    out << YAML::EndMap;

    const ProjectorOptics& p = rig.projector_optics;
    out << YAML::Key << "projector_optics" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "gamma" << YAML::Value;
    real(out, p.gamma);
    out << YAML::Key << "black_level" << YAML::Value;
    real(out, p.black_level);
    out << YAML::Key << "defocus_sigma_px" << YAML::Value;
    real(out, p.defocus_sigma_px);
    out << YAML::EndMap;

    out << YAML::EndMap;
    return yaml_emit::document(out);
}

std::filesystem::path default_rig_path() {
    return std::filesystem::path(FPP_BOARD_DIR) / "sim" / "paper-rig.yaml";
}

std::filesystem::path effects_rig_path() {
    return std::filesystem::path(FPP_BOARD_DIR) / "sim" / "paper-rig-effects.yaml";
}

std::filesystem::path lens_defects_rig_path() {
    return std::filesystem::path(FPP_BOARD_DIR) / "sim" / "paper-rig-lens-defects.yaml";
}

std::filesystem::path prism_projector_rig_path() {
    return std::filesystem::path(FPP_BOARD_DIR) / "sim" / "rig-prism-projector.yaml";
}

std::filesystem::path camera_defect_rig_path() {
    return std::filesystem::path(FPP_BOARD_DIR) / "sim" / "rig-camera-defect.yaml";
}

std::filesystem::path decentred_projector_rig_path() {
    return std::filesystem::path(FPP_BOARD_DIR) / "sim" / "rig-decentred-projector.yaml";
}

} // namespace fpp::sim
