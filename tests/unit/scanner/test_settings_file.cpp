// The settings a person changes on a running scanner
// (fpp/scanner/settings_file.hpp): written atomically in the documented
// form, read back exactly, and every bad file refused naming the file and
// the field.

#include "fpp/scanner/settings_file.hpp"

#include "fpp/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

using fpp::scanner::read_settings_file;
using fpp::scanner::ScannerSettings;
using fpp::scanner::write_settings_file;
namespace fs = std::filesystem;

namespace {

using fpp::test::file_bytes;

// The field of the InputError that reading `text` throws, its message after
// "FILE: FIELD: ".
struct Refusal {
    std::string field, message;
};
Refusal refusal(const std::string& text) {
    fpp::test::TempDir dir;
    const fs::path file = dir / "settings.yaml";
    std::ofstream(file) << text;
    try {
        read_settings_file(file);
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), file) << e.what();
        const std::string prefix = file.string() + ": " + e.field() + ": ";
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
        return {e.field(), what.substr(std::min(prefix.size(), what.size()))};
    }
    ADD_FAILURE() << "accepted:\n" << text;
    return {};
}

TEST(SettingsFile, AbsentFileIsNoSettings) {
    fpp::test::TempDir dir;
    EXPECT_FALSE(read_settings_file(dir / "settings.yaml").has_value());
}

TEST(SettingsFile, WrittenInTheDocumentedFormAndReadBackExactly) {
    fpp::test::TempDir dir;
    const fs::path file = dir / "settings.yaml";
    write_settings_file(file, ScannerSettings{8000});
    EXPECT_EQ(file_bytes(file), "format: fpp-scanner-settings/1\nexposure_us: 8000.0\n");
    for (const double exposure : {10.0, 1e6, 2500.5, 1234.5678901234567}) {
        write_settings_file(file, ScannerSettings{exposure}); // replaces the earlier file
        const auto read = read_settings_file(file);
        ASSERT_TRUE(read.has_value());
        EXPECT_EQ(read->exposure_us, exposure);
    }
    // Replaced in place, nothing left beside it.
    EXPECT_EQ(fpp::test::entries_under(dir.path()), std::vector<fs::path>{file});
}

TEST(SettingsFile, ReadsAFileAPersonWrote) {
    fpp::test::TempDir dir;
    const fs::path file = dir / "settings.yaml";
    std::ofstream(file) << "# kept by the scanner\nexposure_us: 12000   # us\n"
                           "format: \"fpp-scanner-settings/1\"\n";
    const auto read = read_settings_file(file);
    ASSERT_TRUE(read.has_value());
    EXPECT_EQ(read->exposure_us, 12000.0);
}

TEST(SettingsFile, RefusesAnotherFormat) {
    const Refusal r = refusal("format: fpp-scanner-settings/2\nexposure_us: 8000\n");
    EXPECT_EQ(r.field, "format");
    EXPECT_EQ(r.message, "must be fpp-scanner-settings/1 (line 1)");
    EXPECT_EQ(refusal("exposure_us: 8000\n").field, "format"); // missing
}

TEST(SettingsFile, RefusesAnExposureOutsideItsRange) {
    for (const char* value : {"9.99", "1000000.5", "0", "-8000"}) {
        const Refusal r =
            refusal(std::string("format: fpp-scanner-settings/1\nexposure_us: ") + value + "\n");
        EXPECT_EQ(r.field, "exposure_us") << value;
        EXPECT_EQ(r.message, "must be in 10..1000000 (line 2)") << value;
    }
}

TEST(SettingsFile, RefusesMissingUnknownAndMalformedFields) {
    EXPECT_EQ(refusal("format: fpp-scanner-settings/1\n").field, "exposure_us");
    EXPECT_EQ(refusal("format: fpp-scanner-settings/1\nexposure_us: fast\n").field, "exposure_us");
    EXPECT_EQ(refusal("format: fpp-scanner-settings/1\nexposure_us: .nan\n").field, "exposure_us");
    const Refusal unknown = refusal("format: fpp-scanner-settings/1\nexposure_us: 8000\ngain: 2\n");
    EXPECT_EQ(unknown.field, "gain");
    EXPECT_EQ(unknown.message, "unknown key (allowed here: format, exposure_us) (line 3)");
}

TEST(SettingsFile, WritingWhereNoFolderIsIsAnIoError) {
    fpp::test::TempDir dir;
    EXPECT_THROW(write_settings_file(dir / "absent" / "settings.yaml", ScannerSettings{}),
                 fpp::IoError);
}

} // namespace
