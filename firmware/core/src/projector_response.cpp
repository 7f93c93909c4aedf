// The projector response: its monotone interpolation, its fit from a ramp of
// grey levels, and its file (firmware/core/formats/projector-response.md).

#include "fpp/projector_response.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace fpp {

namespace {

namespace fs = std::filesystem;
using yaml_fields::format_real;
using yaml_fields::format_string;
using yaml_fields::item;
using yaml_fields::read_text_file;
using yaml_fields::Reader;

std::string fixed(double value, int digits) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", digits, value);
    return text;
}

// A drive level as people write it: 128, 127.5.
std::string level_text(double level) {
    char text[64];
    std::snprintf(text, sizeof text, "%g", level);
    return text;
}

std::string percent(double fraction) {
    return fixed(100.0 * fraction, 2) + " %";
}

// ---------------------------------------------------------------------------
// Monotone cubic interpolation. Each sample's tangent is the derivative of
// the parabola through it and its neighbours (one-sided at the ends), then
// limited to [0, 3 min(adjacent secants)]: Fritsch and Carlson's sufficient
// condition (alpha, beta in [0, 3]) for a monotone Hermite cubic on
// non-decreasing data, computed per sample so that at() allocates nothing.
// ---------------------------------------------------------------------------

double secant(const std::vector<double>& x, const std::vector<double>& y, std::size_t k) {
    return (y[k + 1] - y[k]) / (x[k + 1] - x[k]);
}

double tangent(const std::vector<double>& x, const std::vector<double>& y, std::size_t k) {
    const std::size_t n = x.size();
    if (n == 2)
        return secant(x, y, 0);
    double m = 0;
    double limit = 0;
    if (k == 0) {
        const double h0 = x[1] - x[0], h1 = x[2] - x[1];
        const double d0 = secant(x, y, 0), d1 = secant(x, y, 1);
        m = ((2 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
        limit = 3 * d0;
    } else if (k == n - 1) {
        const double h0 = x[n - 1] - x[n - 2], h1 = x[n - 2] - x[n - 3];
        const double d0 = secant(x, y, n - 2), d1 = secant(x, y, n - 3);
        m = ((2 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
        limit = 3 * d0;
    } else {
        const double h0 = x[k] - x[k - 1], h1 = x[k + 1] - x[k];
        const double d0 = secant(x, y, k - 1), d1 = secant(x, y, k);
        m = (h1 * d0 + h0 * d1) / (h0 + h1);
        limit = 3 * std::min(d0, d1);
    }
    return std::clamp(m, 0.0, limit);
}

// ---------------------------------------------------------------------------
// The fit.
// ---------------------------------------------------------------------------

fs::path ramp_origin(const ResponseRamp& ramp) {
    return ramp.folder.empty() ? fs::path("ramp.yaml") : ramp.folder / "ramp.yaml";
}

// Samples of one frame as doubles, whatever its depth.
struct FrameSamples {
    const std::uint8_t* u8 = nullptr;
    const std::uint16_t* u16 = nullptr;
    explicit FrameSamples(const Frame& f)
        : u8(f.bit_depth == 8 ? f.u8.data() : nullptr),
          u16(f.bit_depth == 8 ? nullptr : f.u16.data()) {}
    double operator[](std::size_t i) const { return u8 ? double(u8[i]) : double(u16[i]); }
};

struct LevelMean {
    double mean = 0;
    double standard_error = 0;
};

// Trimmed mean of `v` (reordered) and its standard error from the winsorized
// variance (Tukey and McLaughlin 1963): s_w / ((1 - 2g) sqrt(n)).
LevelMean trimmed_mean(std::vector<float>& v, double trim) {
    const std::size_t n = v.size();
    const auto g = static_cast<std::size_t>(std::floor(trim * static_cast<double>(n)));
    const std::size_t lo = g, hi = n - 1 - g;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(lo), v.end());
    if (hi > lo)
        std::nth_element(v.begin() + std::ptrdiff_t(lo) + 1, v.begin() + std::ptrdiff_t(hi),
                         v.end());
    const double low = double(v[lo]), high = double(v[hi]);
    double sum = 0;
    for (std::size_t i = lo; i <= hi; ++i)
        sum += double(v[i]);
    LevelMean r;
    r.mean = sum / static_cast<double>(hi - lo + 1);
    // Winsorized: the trimmed values replaced by the nearest kept one.
    double wsum = sum + static_cast<double>(g) * (low + high);
    const double wmean = wsum / static_cast<double>(n);
    double ss = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double w = i < lo ? low : (i > hi ? high : double(v[i]));
        ss += (w - wmean) * (w - wmean);
    }
    if (n > 1) {
        const double sw = std::sqrt(ss / static_cast<double>(n - 1));
        const double kept = static_cast<double>(hi - lo + 1) / static_cast<double>(n);
        r.standard_error = sw / (kept * std::sqrt(static_cast<double>(n)));
    }
    return r;
}

// Pool adjacent violators: the non-decreasing sequence nearest `y` in least
// squares, each value weighted equally.
void pool_adjacent_violators(std::vector<double>& y) {
    struct Block {
        double sum;
        std::size_t count;
        double mean() const { return sum / static_cast<double>(count); }
    };
    std::vector<Block> blocks;
    for (const double v : y) {
        blocks.push_back({v, 1});
        while (blocks.size() > 1 && blocks[blocks.size() - 2].mean() > blocks.back().mean()) {
            blocks[blocks.size() - 2].sum += blocks.back().sum;
            blocks[blocks.size() - 2].count += blocks.back().count;
            blocks.pop_back();
        }
    }
    std::size_t k = 0;
    for (const Block& b : blocks)
        for (std::size_t i = 0; i < b.count; ++i)
            y[k++] = b.mean();
}

// Which pixels to use; throws when too few are.
std::vector<std::uint8_t> usable_pixels(const ResponseRamp& ramp, const ResponseFitOptions& o,
                                        const fs::path& origin, std::size_t& used) {
    const std::size_t n = ramp.frames[0].size().area();
    const std::size_t levels = ramp.levels.size();
    const std::size_t last = levels - 1;
    const double full = ramp.frames[0].max_value();
    const double saturated = o.saturation_fraction * full;
    const double min_range = o.min_lit_fraction * full;
    std::vector<FrameSamples> frames;
    for (const Frame& f : ramp.frames)
        frames.emplace_back(f);

    // Per pixel: not lit (0), or lit and saturated from frame k on (k + 1;
    // levels + 1 = never saturated).
    std::vector<std::uint16_t> state(n, 0);
    std::size_t lit = 0;
    used = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (frames[last][i] - frames[0][i] < min_range)
            continue;
        ++lit;
        std::size_t k = 0;
        while (k < levels && frames[k][i] < saturated)
            ++k;
        state[i] = static_cast<std::uint16_t>(k + 1);
        used += k == levels ? 1 : 0;
    }
    const auto needed = static_cast<std::size_t>(
        std::max(3.0, std::ceil(o.min_usable_fraction * static_cast<double>(n))));
    if (used >= needed) {
        std::vector<std::uint8_t> usable(n, 0);
        for (std::size_t i = 0; i < n; ++i)
            usable[i] = state[i] == levels + 1 ? 1 : 0;
        return usable;
    }
    const std::string need = " (needs " + percent(o.min_usable_fraction) + " of the " +
                             std::to_string(n) + " camera pixels)";
    if (lit < needed) {
        throw InputError(origin, item("frames", last),
                         "too dark: only " + std::to_string(lit) + " pixels (" +
                             percent(double(lit) / double(n)) + ") brighten by " +
                             fixed(min_range, 1) + " DN or more from level 0 to level 255" + need +
                             "; raise the exposure, or point the projector at the board");
    }
    // Lit pixels still unsaturated at frame k: those saturating later.
    std::vector<std::size_t> first_saturated(levels + 1, 0);
    for (const auto s : state)
        if (s > 0)
            ++first_saturated[s - 1u];
    std::size_t remaining = lit;
    std::size_t k = 0;
    for (; k < levels; ++k) {
        remaining -= first_saturated[k];
        if (remaining < needed)
            break;
    }
    throw InputError(origin, item("frames", k),
                     "saturates: from level " + std::to_string(ramp.levels[k]) + " on only " +
                         std::to_string(remaining) + " of the " + std::to_string(lit) +
                         " lit pixels stay below " + percent(o.saturation_fraction) +
                         " of full scale" + need + "; lower the exposure");
}

// ---------------------------------------------------------------------------
// The file.
// ---------------------------------------------------------------------------

std::string flow_list(const std::vector<double>& values) {
    std::string s = "[";
    for (std::size_t i = 0; i < values.size(); ++i)
        s += (i ? ", " : "") + format_real(values[i]);
    return s + "]";
}

std::vector<double> real_list(const Reader& yaml, const YAML::Node& root, const char* key) {
    const YAML::Node list = yaml.require(root, "", key);
    yaml.expect_list(list, key);
    std::vector<double> values;
    for (std::size_t i = 0; i < list.size(); ++i)
        values.push_back(yaml.real_value(list[i], item(key, i)));
    return values;
}

} // namespace

void ProjectorResponse::validate(const std::filesystem::path& origin) const {
    if (levels.size() < 2)
        throw InputError(origin, "levels",
                         "needs at least 2 levels (0 and 255), got " +
                             std::to_string(levels.size()));
    if (emitted.size() != levels.size())
        throw InputError(origin, "emitted",
                         std::to_string(emitted.size()) + " values for " +
                             std::to_string(levels.size()) + " levels (one per level)");
    for (std::size_t i = 0; i < levels.size(); ++i) {
        if (!std::isfinite(levels[i]))
            throw InputError(origin, item("levels", i), "non-finite number");
        if (!std::isfinite(emitted[i]))
            throw InputError(origin, item("emitted", i), "non-finite number");
        if (i > 0 && !(levels[i] > levels[i - 1]))
            throw InputError(origin, item("levels", i),
                             "levels must be strictly increasing: " + level_text(levels[i]) +
                                 " follows " + level_text(levels[i - 1]));
        if (i > 0 && emitted[i] < emitted[i - 1])
            throw InputError(origin, item("emitted", i),
                             "not monotonic: the light falls from " + format_real(emitted[i - 1]) +
                                 " at level " + level_text(levels[i - 1]) + " to " +
                                 format_real(emitted[i]) + " at level " + level_text(levels[i]));
    }
    if (levels.front() != 0.0)
        throw InputError(origin, item("levels", 0),
                         "must start at drive level 0, got " + level_text(levels.front()));
    if (levels.back() != 255.0)
        throw InputError(origin, item("levels", levels.size() - 1),
                         "must end at drive level 255, got " + level_text(levels.back()));
    if (emitted.front() != 0.0)
        throw InputError(origin, item("emitted", 0),
                         "must start at 0 (the light of level 0 is the zero), got " +
                             format_real(emitted.front()));
    if (emitted.back() != 1.0)
        throw InputError(origin, item("emitted", emitted.size() - 1),
                         "must end at 1 (the light of level 255 is the unit), got " +
                             format_real(emitted.back()));
}

double ProjectorResponse::at(double level) const {
    validate();
    if (std::isnan(level))
        throw std::invalid_argument("ProjectorResponse::at: level is NaN");
    const double x = std::clamp(level, 0.0, 255.0);
    const std::size_t n = levels.size();
    const auto above = std::upper_bound(levels.begin(), levels.end(), x);
    const std::size_t k = std::min(n - 2, static_cast<std::size_t>(std::max<std::ptrdiff_t>(
                                              0, std::distance(levels.begin(), above) - 1)));
    const double h = levels[k + 1] - levels[k];
    const double t = (x - levels[k]) / h;
    const double t2 = t * t, t3 = t2 * t;
    const double value =
        (2 * t3 - 3 * t2 + 1) * emitted[k] + (t3 - 2 * t2 + t) * h * tangent(levels, emitted, k) +
        (-2 * t3 + 3 * t2) * emitted[k + 1] + (t3 - t2) * h * tangent(levels, emitted, k + 1);
    // Rounding can step a hair outside the interval's values.
    return std::clamp(value, emitted[k], emitted[k + 1]);
}

void ResponseFitOptions::validate() const {
    auto check = [](double value, bool ok, const char* field, const char* range) {
        if (!std::isfinite(value) || !ok)
            throw std::invalid_argument(std::string("ResponseFitOptions::") + field + " must be " +
                                        range + ", got " + format_real(value));
    };
    check(min_lit_fraction, min_lit_fraction > 0 && min_lit_fraction < 1, "min_lit_fraction",
          "in (0, 1)");
    check(saturation_fraction, saturation_fraction > 0 && saturation_fraction <= 1,
          "saturation_fraction", "in (0, 1]");
    check(min_usable_fraction, min_usable_fraction > 0 && min_usable_fraction <= 1,
          "min_usable_fraction", "in (0, 1]");
    check(trim_fraction, trim_fraction >= 0 && trim_fraction <= 0.45, "trim_fraction",
          "in [0, 0.45]");
    check(monotonic_sigmas, monotonic_sigmas > 0, "monotonic_sigmas", "> 0");
    check(min_monotonic_drop, min_monotonic_drop >= 0, "min_monotonic_drop", ">= 0");
}

ProjectorResponse fit_projector_response(const ResponseRamp& ramp,
                                         const ResponseFitOptions& options) {
    options.validate();
    const fs::path origin = ramp_origin(ramp);
    validate_response_ramp(ramp, origin);
    std::size_t used = 0;
    const std::vector<std::uint8_t> usable = usable_pixels(ramp, options, origin, used);

    const std::size_t n = usable.size();
    const std::size_t last = ramp.levels.size() - 1;
    const FrameSamples black(ramp.frames[0]), white(ramp.frames[last]);
    std::vector<LevelMean> means(ramp.levels.size());
    means[last].mean = 1.0;
    std::vector<float> values;
    values.reserve(used);
    for (std::size_t k = 1; k < last; ++k) {
        const FrameSamples frame(ramp.frames[k]);
        values.clear();
        for (std::size_t i = 0; i < n; ++i) {
            if (!usable[i])
                continue;
            values.push_back(static_cast<float>((frame[i] - black[i]) / (white[i] - black[i])));
        }
        means[k] = trimmed_mean(values, options.trim_fraction);
    }

    // A fall beyond the noise is a real defect of the measurement (auto
    // exposure, a dynamic-contrast projector, something moved): refuse it.
    for (std::size_t k = 1; k <= last; ++k) {
        const double drop = means[k - 1].mean - means[k].mean;
        const double sigma = std::hypot(means[k - 1].standard_error, means[k].standard_error);
        const double tolerance =
            std::max(options.monotonic_sigmas * sigma, options.min_monotonic_drop);
        if (drop > tolerance) {
            throw InputError(origin, item("levels", k),
                             "the response is not monotonic: the light falls from " +
                                 fixed(means[k - 1].mean, 4) + " at level " +
                                 std::to_string(ramp.levels[k - 1]) + " to " +
                                 fixed(means[k].mean, 4) + " at level " +
                                 std::to_string(ramp.levels[k]) + " (noise sigma " +
                                 fixed(sigma, 4) +
                                 "); keep the exposure, the projector's "
                                 "dynamic contrast and the board fixed and record the ramp again");
        }
    }
    ProjectorResponse response;
    response.levels.assign(ramp.levels.begin(), ramp.levels.end());
    for (const LevelMean& m : means)
        response.emitted.push_back(m.mean);
    pool_adjacent_violators(response.emitted);
    for (double& e : response.emitted)
        e = std::clamp(e, 0.0, 1.0);
    response.emitted.front() = 0.0;
    response.emitted.back() = 1.0;
    response.pixels_used = used;
    response.ramp = ramp.folder.string();
    return response;
}

std::string projector_response_to_yaml(const ProjectorResponse& response) {
    response.validate();
    std::string s = std::string("format: ") + kProjectorResponseFormat + "\n";
    s += "levels: " + flow_list(response.levels) + "\n";
    s += "emitted: " + flow_list(response.emitted) + "\n";
    s += "pixels_used: " + std::to_string(response.pixels_used) + "\n";
    if (!response.ramp.empty())
        s += "ramp: " + format_string(response.ramp) + "\n";
    return s;
}

void save_projector_response(const std::filesystem::path& path, const ProjectorResponse& response) {
    response.validate(path);
    write_file_atomically(path, projector_response_to_yaml(response));
}

ProjectorResponse parse_projector_response(const std::string& yaml_text,
                                           const std::filesystem::path& origin) {
    try {
        const Reader yaml(origin);
        const YAML::Node root = yaml.load(yaml_text);
        if (!root.IsMap())
            yaml.fail(root, "",
                      std::string("must be a YAML map with format: ") + kProjectorResponseFormat);
        const YAML::Node format_node = yaml.require(root, "", "format");
        const std::string format = yaml.string_value(format_node, "format");
        if (format != kProjectorResponseFormat)
            yaml.fail(format_node, "format",
                      "unknown format '" + format + "' (this reader knows " +
                          kProjectorResponseFormat + ")");
        yaml.expect_map(root, "", {"format", "levels", "emitted", "pixels_used", "ramp"});
        ProjectorResponse r;
        r.levels = real_list(yaml, root, "levels");
        r.emitted = real_list(yaml, root, "emitted");
        if (const YAML::Node v = root["pixels_used"]; v.IsDefined()) {
            const double count = yaml.real_value(v, "pixels_used");
            if (count < 0 || count != std::floor(count) || count > 9007199254740992.0)
                yaml.fail(v, "pixels_used", "must be a whole number of pixels >= 0");
            r.pixels_used = static_cast<std::size_t>(count);
        }
        if (const YAML::Node v = root["ramp"]; v.IsDefined())
            r.ramp = yaml.string_value(v, "ramp");
        r.validate(origin);
        return r;
    } catch (const YAML::Exception& e) {
        throw InputError(origin, "", std::string("cannot be read as YAML: ") + e.what());
    }
}

ProjectorResponse load_projector_response(const std::filesystem::path& path) {
    return parse_projector_response(read_text_file(path), path);
}

} // namespace fpp
