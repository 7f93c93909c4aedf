// The shared YAML field readers (fpp/yaml_fields.hpp): the parts that the
// capture-set, rig and scene tests do not reach directly, and the writers'
// scalar spellings reading back through the readers.

#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

namespace fs = std::filesystem;
using fpp::yaml_fields::Reader;

namespace {

const fs::path kOrigin = "/rigs/bench.yaml";

// Runs f; expects an InputError naming kOrigin (or `file`) and exactly `field`.
template <class F>
void expect_input_error(F&& f, const std::string& field, const fs::path& file = kOrigin) {
    try {
        f();
        ADD_FAILURE() << "no InputError for " << field;
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), file) << e.what();
        EXPECT_EQ(e.field(), field) << e.what();
        EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
}

TEST(YamlFields, PathsOfFields) {
    EXPECT_EQ(fpp::yaml_fields::child("", "format"), "format");
    EXPECT_EQ(fpp::yaml_fields::child("camera", "width"), "camera.width");
    EXPECT_EQ(fpp::yaml_fields::item("shapes", 3), "shapes[3]");
    EXPECT_EQ(fpp::yaml_fields::child(fpp::yaml_fields::item("shapes", 0), "centre"),
              "shapes[0].centre");
}

TEST(YamlFields, RealArrayNeedsExactlyNFiniteReals) {
    const Reader in(kOrigin);
    const YAML::Node root = in.load("a: [1, -2.5, 3e2]\nb: [1, 2]\nc: [1, .inf, 3]\nd: 4\n");
    const auto a = in.real_array<3>(root["a"], "a");
    EXPECT_EQ(a[0], 1.0);
    EXPECT_EQ(a[1], -2.5);
    EXPECT_EQ(a[2], 300.0);
    expect_input_error([&] { in.real_array<3>(root["b"], "b"); }, "b");
    expect_input_error([&] { in.real_array<3>(root["c"], "c"); }, "c[1]");
    expect_input_error([&] { in.real_array<3>(root["d"], "d"); }, "d");
}

TEST(YamlFields, OptionalRealFallsBackOnlyWhenAbsent) {
    const Reader in(kOrigin);
    const YAML::Node root = in.load("sensor: {ambient: 5, gain: , noise: high}\n");
    const YAML::Node sensor = root["sensor"];
    EXPECT_EQ(in.real_value_or(sensor, "sensor", "ambient", 0.0), 5.0);
    EXPECT_EQ(in.real_value_or(sensor, "sensor", "absent", 0.25), 0.25);
    // Present but empty or not a number is an error, not the fallback.
    expect_input_error([&] { in.real_value_or(sensor, "sensor", "gain", 1.0); }, "sensor.gain");
    expect_input_error([&] { in.real_value_or(sensor, "sensor", "noise", 1.0); }, "sensor.noise");
}

TEST(YamlFields, ListOfAGivenSize) {
    const Reader in(kOrigin);
    const YAML::Node root = in.load("pair: [1, 2]\nmap: {a: 1}\n");
    in.expect_list(root["pair"], "pair", 2);
    expect_input_error([&] { in.expect_list(root["pair"], "pair", 3); }, "pair");
    expect_input_error([&] { in.expect_list(root["map"], "map", 1); }, "map");
}

TEST(YamlFields, LoadFileNamesTheFile) {
    fpp::test::TempDir dir;
    const fs::path path = dir / "rig.yaml";
    std::ofstream(path) << "format: fpp-rig/1\nwidth: 1.5\n";
    const Reader in(path);
    const YAML::Node root = in.load_file();
    EXPECT_EQ(in.string_value(root["format"], "format"), "fpp-rig/1");
    expect_input_error([&] { in.int_value(root["width"], "width"); }, "width", path);
    expect_input_error([&] { Reader(dir / "none.yaml").load_file(); }, "", dir / "none.yaml");
    expect_input_error([&] { Reader(dir.path()).load_file(); }, "", dir.path());
}

TEST(YamlFields, WrittenRealsReadBackExactly) {
    const Reader in(kOrigin);
    for (const double v : {0.0, 240.0, -3.0, 0.1, 1.0 / 3.0, -163.71, 1e-300, 6.02214076e23,
                           std::numeric_limits<double>::max()}) {
        const std::string text = fpp::yaml_fields::format_real(v);
        EXPECT_EQ(in.real_value(in.load("v: " + text)["v"], "v"), v) << text;
    }
    EXPECT_EQ(fpp::yaml_fields::format_real(240.0), "240.0");
    EXPECT_EQ(fpp::yaml_fields::format_real(0.5), "0.5");
}

TEST(YamlFields, WrittenStringsReadBackExactly) {
    const Reader in(kOrigin);
    for (const std::string s :
         {"paper-rig", "", "round \"trip\"", "back\\slash", "two\nlines", "tab\there", "true",
          "null", "42", "1.5", "-dash", "a: b", "# not a comment", "[list]", "yes"}) {
        const std::string text = fpp::yaml_fields::format_string(s);
        EXPECT_EQ(in.string_value(in.load("v: " + text)["v"], "v"), s) << text;
    }
    // Plain where that is unambiguous.
    EXPECT_EQ(fpp::yaml_fields::format_string("paper-rig"), "paper-rig");
    EXPECT_EQ(fpp::yaml_fields::format_string("true"), "\"true\"");
}

} // namespace
