// The artefact file reader (firmware/core/formats/artefact.md).

#include "fpp/calib/artefact.hpp"

#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <string>

namespace fpp::calib {

namespace {

using yaml_fields::Reader;

constexpr const char* kFormat = "fpp-artefact/1";
// Bounds that catch a unit mistake (micrometres written as mm) or a typing
// slip rather than limits of the method.
constexpr double kMinDiameterMm = 1, kMaxDiameterMm = 1000;
constexpr double kMaxLengthMm = 10000;
constexpr double kMaxUncertaintyMm = 0.1;
constexpr double kMaxFlatnessMm = 1;
constexpr std::size_t kMaxNameLength = 128;

std::string number(double v) {
    return yaml_fields::format_real(v);
}

// A real in [lo, hi] (inclusive), or in (lo, hi] when lo_open.
double bounded(const Reader& in, const YAML::Node& node, const std::string& field, double lo,
               double hi, bool lo_open = false) {
    const double v = in.real_value(node, field);
    if ((lo_open ? !(v > lo) : !(v >= lo)) || !(v <= hi))
        in.fail(node, field,
                number(v) + " is outside " + (lo_open ? "(" : "[") + number(lo) + ", " +
                    number(hi) + "] mm");
    return v;
}

constexpr EnumName<ArtefactKind> kArtefactKindNames[] = {
    {ArtefactKind::ball_bar, "ball-bar"},
    {ArtefactKind::sphere, "sphere"},
    {ArtefactKind::plane, "plane"},
};

ArtefactKind parse_kind(const Reader& in, const YAML::Node& node) {
    const std::string kind = in.string_value(node, "kind");
    if (const auto k = value_of(kArtefactKindNames, kind))
        return *k;
    in.fail(node, "kind", unknown_name_message(kArtefactKindNames, "kind", kind));
}

void read_spheres(const Reader& in, const YAML::Node& root, Artefact& a) {
    const std::size_t count = a.kind == ArtefactKind::ball_bar ? 2 : 1;
    const YAML::Node list = in.require(root, "", "sphere_diameters_mm");
    in.expect_list(list, "sphere_diameters_mm");
    if (list.size() != count)
        in.fail(list, "sphere_diameters_mm",
                std::string("a ") + to_string(a.kind) + " has " + std::to_string(count) +
                    (count == 1 ? " sphere" : " spheres") + ": give " + std::to_string(count) +
                    (count == 1 ? " diameter" : " diameters") + ", got " +
                    std::to_string(list.size()));
    for (std::size_t i = 0; i < count; ++i)
        a.sphere_diameters_mm.push_back(bounded(in, list[i],
                                                yaml_fields::item("sphere_diameters_mm", i),
                                                kMinDiameterMm, kMaxDiameterMm));
    if (a.kind != ArtefactKind::ball_bar)
        return;
    const YAML::Node distance = in.require(root, "", "centre_distance_mm");
    a.centre_distance_mm = bounded(in, distance, "centre_distance_mm", 0, kMaxLengthMm, true);
    const double touching = 0.5 * (a.sphere_diameters_mm[0] + a.sphere_diameters_mm[1]);
    if (!(a.centre_distance_mm > touching))
        in.fail(distance, "centre_distance_mm",
                number(a.centre_distance_mm) + " mm would make the spheres touch or overlap " +
                    "(their radii add up to " + number(touching) + " mm)");
}

void read_plane(const Reader& in, const YAML::Node& root, Artefact& a) {
    const YAML::Node size = in.require(root, "", "plane_size_mm");
    in.expect_list(size, "plane_size_mm", 2);
    a.plane_width_mm = bounded(in, size[0], "plane_size_mm[0]", 0, kMaxLengthMm, true);
    a.plane_height_mm = bounded(in, size[1], "plane_size_mm[1]", 0, kMaxLengthMm, true);
    a.flatness_mm = in.real_value(in.require(root, "", "flatness_mm"), "flatness_mm");
    if (!(a.flatness_mm >= 0) || !(a.flatness_mm < kMaxFlatnessMm))
        in.fail(root["flatness_mm"], "flatness_mm",
                number(a.flatness_mm) + " is outside [0, " + number(kMaxFlatnessMm) +
                    ") mm (a certified flat is flat to micrometres: are these micrometres?)");
}

} // namespace

const char* to_string(ArtefactKind kind) {
    return name_of(kArtefactKindNames, kind);
}

Artefact parse_artefact(const std::string& text, const std::filesystem::path& origin) {
    const Reader in(origin);
    const YAML::Node root = in.load(text);
    if (!root.IsMap())
        in.fail(root, "(top level)", std::string("expected a map with format: ") + kFormat);
    const YAML::Node format = in.require(root, "", "format");
    if (in.string_value(format, "format") != kFormat)
        in.fail(format, "format",
                "unknown format '" + in.string_value(format, "format") + "' (expected " + kFormat +
                    ")");
    Artefact a;
    a.origin = origin;
    a.kind = parse_kind(in, in.require(root, "", "kind"));
    // Each kind has its own keys; one of another kind is refused, not ignored.
    switch (a.kind) {
    case ArtefactKind::ball_bar:
        in.expect_map(root, "",
                      {"format", "kind", "name", "sphere_diameters_mm", "centre_distance_mm",
                       "uncertainty_mm"});
        break;
    case ArtefactKind::sphere:
        in.expect_map(root, "",
                      {"format", "kind", "name", "sphere_diameters_mm", "uncertainty_mm"});
        break;
    case ArtefactKind::plane:
        in.expect_map(root, "",
                      {"format", "kind", "name", "plane_size_mm", "flatness_mm", "uncertainty_mm"});
        break;
    }
    if (const YAML::Node name = root["name"]; name.IsDefined() && !name.IsNull()) {
        a.name = in.string_value(name, "name");
        if (a.name.empty() || a.name.size() > kMaxNameLength)
            in.fail(name, "name", "must be 1 to " + std::to_string(kMaxNameLength) + " characters");
    }
    if (a.kind == ArtefactKind::plane)
        read_plane(in, root, a);
    else
        read_spheres(in, root, a);
    const YAML::Node uncertainty = in.require(root, "", "uncertainty_mm");
    a.uncertainty_mm = in.real_value(uncertainty, "uncertainty_mm");
    if (!(a.uncertainty_mm >= 0) || !(a.uncertainty_mm < kMaxUncertaintyMm))
        in.fail(uncertainty, "uncertainty_mm",
                number(a.uncertainty_mm) + " is outside [0, " + number(kMaxUncertaintyMm) +
                    ") mm (a certificate states micrometres: are these micrometres?)");
    return a;
}

Artefact read_artefact(const std::filesystem::path& path) {
    return parse_artefact(yaml_fields::read_text_file(path), path);
}

} // namespace fpp::calib
