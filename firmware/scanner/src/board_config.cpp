#include "fpp/scanner/board_config.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/sequences.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <stdexcept>

namespace fpp::scanner {

namespace {

using yaml_fields::child;
using yaml_fields::Reader;

// "auto" or WIDTHxHEIGHT, each 1 to 5 digits without a leading zero.
bool valid_mode(const std::string& mode) {
    if (mode == "auto")
        return true;
    const auto x = mode.find('x');
    if (x == std::string::npos)
        return false;
    auto number = [](const std::string& s) {
        return !s.empty() && s.size() <= 5 && s[0] != '0' &&
               std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
    };
    return number(mode.substr(0, x)) && number(mode.substr(x + 1));
}

class BoardParser {
public:
    explicit BoardParser(const std::filesystem::path& origin) : r_(origin) {}

    int int_in(const YAML::Node& map, const std::string& parent, std::string_view key, int lo,
               int hi) const {
        const std::string field = child(parent, key);
        const int v = r_.int_value(r_.require(map, parent, key), field);
        if (v < lo || v > hi)
            r_.fail(map[std::string(key)], field,
                    "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
        return v;
    }
    std::string text(const YAML::Node& map, const std::string& parent, std::string_view key) const {
        return r_.string_value(r_.require(map, parent, key), child(parent, key));
    }
    std::string non_empty(const YAML::Node& map, const std::string& parent,
                          std::string_view key) const {
        std::string s = text(map, parent, key);
        if (s.empty())
            r_.fail(map[std::string(key)], child(parent, key), "must not be empty");
        return s;
    }
    bool flag(const YAML::Node& map, const std::string& parent, std::string_view key) const {
        return r_.bool_value(r_.require(map, parent, key), child(parent, key));
    }
    std::filesystem::path path(const YAML::Node& map, const std::string& parent,
                               std::string_view key) const {
        std::filesystem::path p = non_empty(map, parent, key);
        return p.is_absolute() ? p : r_.origin().parent_path() / p;
    }

    BoardConfig parse(const std::string& yaml_text) const {
        const YAML::Node root = r_.load(yaml_text);
        r_.expect_map(root, "",
                      {"format", "name", "display", "gpio", "camera", "sequence", "table",
                       "projector_response", "hdr", "points", "store", "timing", "sim", "http",
                       "settings"});
        BoardConfig c;
        c.file = r_.origin();
        if (text(root, "", "format") != kBoardConfigFormat)
            r_.fail(root["format"], "format", std::string("must be ") + kBoardConfigFormat);
        c.name = non_empty(root, "", "name");
        parse_display(r_.require(root, "", "display"), c.display);
        parse_gpio(r_.require(root, "", "gpio"), c.gpio);
        parse_camera(r_.require(root, "", "camera"), c.camera);
        parse_sequence_field(r_.require(root, "", "sequence"), c);
        if (root["table"] && !root["table"].IsNull())
            c.table = path(root, "", "table");
        if (root["projector_response"] && !root["projector_response"].IsNull())
            c.projector_response = path(root, "", "projector_response");
        if (root["hdr"] && !root["hdr"].IsNull())
            c.hdr = parse_hdr(root["hdr"]);
        if (root["points"] && !root["points"].IsNull())
            parse_points(root["points"], c);
        parse_store(r_.require(root, "", "store"), c.store);
        parse_timing(r_.require(root, "", "timing"), c.timing);
        if (root["http"] && !root["http"].IsNull())
            c.http = parse_http(root["http"]);
        if (root["settings"] && !root["settings"].IsNull())
            c.settings_file = path(root, "", "settings");
        if (c.camera.driver == CameraDriver::sim && !root["sim"])
            r_.fail("sim", "missing field (camera.driver is sim)");
        if (root["sim"]) {
            c.sim = parse_sim(root["sim"]);
            if (c.camera.driver == CameraDriver::aravis)
                check_gige_link(root, c);
            if (c.sim->camera_only)
                check_camera_only(root, c);
            // A session scene moves its board at every camera start with
            // frames: HDR's passes would each see another pose.
            if (c.hdr && c.sim->scene.starts_with("session:"))
                r_.fail(root["hdr"], "hdr", "not with a session scene (sim.scene session:...)");
        }
        return c;
    }

private:
    void parse_display(const YAML::Node& n, DisplayConfig& d) const {
        r_.expect_map(n, "display", {"card", "connector", "mode"});
        d.card = non_empty(n, "display", "card");
        d.connector = non_empty(n, "display", "connector");
        d.mode = non_empty(n, "display", "mode");
        if (!valid_mode(d.mode))
            r_.fail(n["mode"], "display.mode", "must be auto or WIDTHxHEIGHT (e.g. 1280x800)");
    }
    void parse_gpio(const YAML::Node& n, GpioConfig& g) const {
        r_.expect_map(n, "gpio",
                      {"chip", "trigger_line", "button_line", "led_line", "trigger_active_low",
                       "button_active_low", "led_active_low", "debounce_ms"});
        g.chip = non_empty(n, "gpio", "chip");
        g.trigger_line = int_in(n, "gpio", "trigger_line", 0, 4095);
        g.button_line = int_in(n, "gpio", "button_line", 0, 4095);
        g.led_line = int_in(n, "gpio", "led_line", 0, 4095);
        if (g.trigger_line == g.button_line || g.trigger_line == g.led_line ||
            g.button_line == g.led_line)
            r_.fail(n, "gpio", "trigger_line, button_line and led_line must differ");
        g.trigger_active_low = flag(n, "gpio", "trigger_active_low");
        g.button_active_low = flag(n, "gpio", "button_active_low");
        g.led_active_low = flag(n, "gpio", "led_active_low");
        g.debounce = std::chrono::milliseconds(int_in(n, "gpio", "debounce_ms", 0, 1000));
    }
    void parse_camera(const YAML::Node& n, CameraConfig& c) const {
        r_.expect_map(n, "camera",
                      {"driver", "device", "pixel_format", "exposure_us", "trigger",
                       "trigger_source", "packet_size", "buffer_count", "frame_timeout_ms",
                       "noise"});
        const std::string driver = text(n, "camera", "driver");
        if (const auto d = value_of(kCameraDriverNames, driver))
            c.driver = *d;
        else
            r_.fail(n["driver"], "camera.driver",
                    "must be " + names_list(kCameraDriverNames, " or "));
        c.device = text(n, "camera", "device");
        auto& s = c.settings;
        s.pixel_format = text(n, "camera", "pixel_format");
        if (s.pixel_format != "Mono8" && s.pixel_format != "Mono10" && s.pixel_format != "Mono12" &&
            s.pixel_format != "Mono16")
            r_.fail(n["pixel_format"], "camera.pixel_format",
                    "must be Mono8, Mono10, Mono12 or Mono16");
        s.exposure_us = r_.real_value(r_.require(n, "camera", "exposure_us"), "camera.exposure_us");
        if (!(s.exposure_us >= 1.0 && s.exposure_us <= 1e6))
            r_.fail(n["exposure_us"], "camera.exposure_us", "must be in 1..1000000");
        const std::string trigger = text(n, "camera", "trigger");
        if (const auto t = value_of(drivers::kTriggerModeNames, trigger))
            s.trigger = *t;
        else
            r_.fail(n["trigger"], "camera.trigger",
                    "must be " + names_list(drivers::kTriggerModeNames, " or "));
        s.trigger_source = non_empty(n, "camera", "trigger_source");
        s.packet_size = int_in(n, "camera", "packet_size", 0, 16384);
        s.buffer_count = int_in(n, "camera", "buffer_count", 2, 64);
        s.frame_timeout =
            std::chrono::milliseconds(int_in(n, "camera", "frame_timeout_ms", 1, 60000));
        if (n["noise"] && !n["noise"].IsNull())
            c.noise = parse_noise(n["noise"]);
    }
    double real_in(const YAML::Node& map, const std::string& parent, std::string_view key,
                   double lo, double hi, const std::string& range) const {
        const std::string field = child(parent, key);
        const double v = r_.real_value(r_.require(map, parent, key), field);
        if (!(v >= lo && v <= hi))
            r_.fail(map[std::string(key)], field, "must be in " + range);
        return v;
    }
    CameraNoise parse_noise(const YAML::Node& n) const {
        const std::string parent = "camera.noise";
        r_.expect_map(n, parent, {"read_noise_dn", "gain_e_per_dn", "sensor_bit_depth"});
        CameraNoise noise;
        noise.read_noise_dn = real_in(n, parent, "read_noise_dn", 0, 1e4, "0..10000");
        noise.gain_e_per_dn = real_in(n, parent, "gain_e_per_dn", 0, 1e6, "0..1000000");
        noise.sensor_bit_depth = int_in(n, parent, "sensor_bit_depth", 8, 16);
        return noise;
    }
    HdrConfig parse_hdr(const YAML::Node& n) const {
        r_.expect_map(n, "hdr", {"exposures_us", "auto"});
        HdrConfig h;
        if (static_cast<bool>(n["exposures_us"]) == static_cast<bool>(n["auto"]))
            r_.fail(n, "hdr", "give exactly one of exposures_us and auto");
        if (n["exposures_us"]) {
            const YAML::Node list = n["exposures_us"];
            r_.expect_list(list, "hdr.exposures_us");
            if (list.size() < 1 || list.size() > 8)
                r_.fail(list, "hdr.exposures_us", "must list 1 to 8 exposures");
            for (std::size_t i = 0; i < list.size(); ++i) {
                const std::string field = "hdr.exposures_us[" + std::to_string(i) + "]";
                const double e = r_.real_value(list[i], field);
                if (!(e >= 1.0 && e <= 1e7))
                    r_.fail(list[i], field, "must be in 1..10000000");
                h.exposures_us.push_back(e);
            }
            return h;
        }
        const YAML::Node a = n["auto"];
        r_.expect_map(a, "hdr.auto", {"max_saturated", "passes", "ratio", "longest_us"});
        h.automatic = true;
        h.max_saturated = real_in(a, "hdr.auto", "max_saturated", 0, 0.99, "0..0.99");
        h.passes = int_in(a, "hdr.auto", "passes", 1, 8);
        h.ratio = real_in(a, "hdr.auto", "ratio", 1.5, 64, "1.5..64");
        if (a["longest_us"])
            h.longest_us = real_in(a, "hdr.auto", "longest_us", 1, 1e7, "1..10000000");
        return h;
    }
    void parse_points(const YAML::Node& n, BoardConfig& c) const {
        r_.expect_map(n, "points", {"max_sigma_z_mm"});
        if (n["max_sigma_z_mm"]) {
            c.points.max_sigma_z_mm =
                real_in(n, "points", "max_sigma_z_mm", 1e-6, 1e3, "(0, 1000]");
            if (!c.camera.noise)
                r_.fail(n["max_sigma_z_mm"], "points.max_sigma_z_mm",
                        "needs camera.noise (the prediction of sigma_z comes from it)");
        }
    }
    void parse_sequence_field(const YAML::Node& n, BoardConfig& c) const {
        if (n.IsScalar()) {
            c.sequence_name = r_.string_value(n, "sequence");
            const auto names = standard_sequence_names();
            if (std::find(names.begin(), names.end(), c.sequence_name) == names.end())
                r_.fail(n, "sequence", "unknown sequence name '" + c.sequence_name + "'");
            return;
        }
        r_.expect_list(n, "sequence");
        // The blocks are the capture-set spec's: let its reader check them
        // (field names stay "sequence[i].<key>").
        YAML::Emitter out;
        out << YAML::BeginMap << YAML::Key << "sequence" << YAML::Value << n << YAML::EndMap;
        c.sequence_blocks = parse_sequence(out.c_str(), r_.origin());
        if (c.sequence_blocks.empty())
            r_.fail(n, "sequence", "must not be empty");
    }
    void parse_store(const YAML::Node& n, StoreConfig& s) const {
        r_.expect_map(n, "store", {"directory", "max_mb"});
        s.directory = path(n, "store", "directory");
        s.max_bytes = static_cast<std::uint64_t>(int_in(n, "store", "max_mb", 1, 1 << 30)) << 20;
    }
    void parse_timing(const YAML::Node& n, TimingConfig& t) const {
        r_.expect_map(n, "timing", {"settle_us", "trigger_pulse_us", "flip_timeout_ms"});
        t.settle = std::chrono::microseconds(int_in(n, "timing", "settle_us", 0, 1'000'000));
        t.trigger_pulse =
            std::chrono::microseconds(int_in(n, "timing", "trigger_pulse_us", 1, 100'000));
        t.flip_timeout =
            std::chrono::milliseconds(int_in(n, "timing", "flip_timeout_ms", 1, 10'000));
    }
    HttpConfig parse_http(const YAML::Node& n) const {
        r_.expect_map(n, "http",
                      {"listen", "token_file", "max_connections", "timeout_s", "web_root"});
        HttpConfig h;
        h.listen = non_empty(n, "http", "listen");
        try {
            (void)parse_listen_address(h.listen);
        } catch (const std::invalid_argument& e) {
            r_.fail(n["listen"], "http.listen", e.what());
        }
        h.token_file = path(n, "http", "token_file");
        if (n["max_connections"])
            h.max_connections = int_in(n, "http", "max_connections", 1, 1024);
        if (n["timeout_s"])
            h.timeout = std::chrono::seconds(int_in(n, "http", "timeout_s", 1, 3600));
        if (n["web_root"])
            h.web_root = path(n, "http", "web_root");
        return h;
    }

    // The virtual scanner behind a real GigE Vision link: its frames go
    // through Aravis's fake camera, which has no line trigger and stamps
    // frames on the host's monotonic clock, to the Aravis driver by address.
    void check_gige_link(const YAML::Node& root, const BoardConfig& c) const {
        const YAML::Node camera = root["camera"];
        if (c.camera.settings.trigger != drivers::TriggerMode::software)
            r_.fail(camera["trigger"], "camera.trigger",
                    "must be software with a sim section (the fake GigE camera has no line "
                    "trigger)");
        if (c.camera.device.empty())
            r_.fail(camera["device"], "camera.device",
                    "must be the local address the fake GigE camera listens on (e.g. "
                    "127.0.0.1) with a sim section");
        if (c.sim->virtual_clock)
            r_.fail(root["sim"]["clock"], "sim.clock",
                    "must be steady with camera.driver aravis (frames carry host time)");
    }

    // Real display and lines, simulated camera: nothing wires the trigger
    // line to it, and the display's flip events carry the host's time.
    void check_camera_only(const YAML::Node& root, const BoardConfig& c) const {
        if (c.camera.settings.trigger != drivers::TriggerMode::software)
            r_.fail(root["camera"]["trigger"], "camera.trigger",
                    "must be software with sim.camera_only (no line reaches a simulated camera)");
        if (c.sim->virtual_clock)
            r_.fail(root["sim"]["clock"], "sim.clock",
                    "must be steady with sim.camera_only (the display's flips carry host time)");
    }

    SimConfig parse_sim(const YAML::Node& n) const {
        r_.expect_map(
            n, "sim",
            {"rig", "scene", "binning", "flip_latency_us", "clock", "seed", "camera_only"});
        SimConfig s;
        s.rig = path(n, "sim", "rig");
        s.scene = non_empty(n, "sim", "scene");
        if (s.scene.ends_with(".yaml"))
            s.scene = path(n, "sim", "scene").string();
        s.binning = int_in(n, "sim", "binning", 1, 8);
        s.flip_latency =
            std::chrono::microseconds(int_in(n, "sim", "flip_latency_us", 0, 1'000'000));
        const std::string clock = text(n, "sim", "clock");
        if (clock == "virtual")
            s.virtual_clock = true;
        else if (clock == "steady")
            s.virtual_clock = false;
        else
            r_.fail(n["clock"], "sim.clock", "must be virtual or steady");
        s.seed = static_cast<std::uint64_t>(int_in(n, "sim", "seed", 0, 1 << 30));
        if (n["camera_only"])
            s.camera_only = flag(n, "sim", "camera_only");
        return s;
    }

    Reader r_;
};

} // namespace

ListenAddress parse_listen_address(const std::string& text) {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0)
        throw std::invalid_argument("'" + text + "' must be ADDRESS:PORT (e.g. 0.0.0.0:8080)");
    ListenAddress a;
    a.host = text.substr(0, colon);
    const std::string port = text.substr(colon + 1);
    int value = -1;
    const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
    if (port.empty() || ec != std::errc() || end != port.data() + port.size() || value < 0 ||
        value > 65535)
        throw std::invalid_argument("'" + text + "': the port must be 0..65535");
    a.port = value;
    return a;
}

Sequence BoardConfig::sequence(Size projector) const {
    if (!sequence_name.empty()) {
        try {
            return standard_sequence(sequence_name, projector);
        } catch (const std::invalid_argument& e) {
            throw InputError(file, "sequence", e.what());
        }
    }
    validate_sequence(sequence_blocks, projector, file);
    return sequence_blocks;
}

BoardConfig parse_board_config(const std::string& yaml_text, const std::filesystem::path& origin) {
    return BoardParser(origin).parse(yaml_text);
}

BoardConfig read_board_config(const std::filesystem::path& path) {
    return parse_board_config(yaml_fields::read_text_file(path), path);
}

} // namespace fpp::scanner
