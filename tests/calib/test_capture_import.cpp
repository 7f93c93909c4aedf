// Capture sets from other tools' frames (fpp/calib/capture_import.hpp), the
// parts below the command: the tools' names, the frame files found in
// capture order (by their last number, else by name), the frame order of
// SLStudio's modulated codec, the sequences of a few codecs and the
// refusals of options no tool can have used. (The command on real and
// rendered captures, and its refusals: CliImport, ImportRealCapture,
// ImportRendered.)

#include "fpp/calib/capture_import.hpp"

#include "fpp/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

using fpp::InputError;
using fpp::calib::ImportOptions;
using fpp::calib::ImportTool;
namespace fs = std::filesystem;

namespace {

// The names of `folder`'s frame files as list_frame_files orders them.
std::vector<std::string> listed(const fs::path& folder) {
    std::vector<std::string> names;
    for (const fs::path& p : fpp::calib::list_frame_files(folder))
        names.push_back(p.filename().string());
    return names;
}

void touch(const fs::path& file) {
    std::ofstream(file) << "";
}

struct Refusal {
    std::string field, message;
};
Refusal refusal(const ImportOptions& options) {
    try {
        fpp::calib::import_sequence(options, "/frames");
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), "/frames");
        return {e.field(), std::string(e.what()).substr(("/frames: " + e.field() + ": ").size())};
    }
    return {"accepted", ""};
}

TEST(CaptureImport, ToolNames) {
    for (const ImportTool tool : {ImportTool::slstudio, ImportTool::slmaster, ImportTool::opencv})
        EXPECT_EQ(fpp::calib::parse_import_tool(fpp::calib::to_string(tool)), tool);
    EXPECT_STREQ(fpp::calib::to_string(ImportTool::slmaster), "slmaster");
    try {
        fpp::calib::parse_import_tool("matlab");
        FAIL() << "took matlab";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "unknown tool 'matlab' (slstudio, slmaster, opencv)");
    }
}

TEST(CaptureImport, FramesInCaptureOrderByTheirLastNumber) {
    fpp::test::TempDir dir;
    for (const char* name : {"frameSeq_10.png", "frameSeq_2.PNG", "frameSeq_1.bmp",
                             "cam0_frame3.tif", "frameSeq_4.TIFF", "notes.txt", "frameSeq_5.jpg"})
        touch(dir / name);
    fs::create_directories(dir / "frameSeq_0.png"); // a folder, not a frame
    EXPECT_EQ(listed(dir.path()),
              (std::vector<std::string>{"frameSeq_1.bmp", "frameSeq_2.PNG", "cam0_frame3.tif",
                                        "frameSeq_4.TIFF", "frameSeq_10.png"}));
}

TEST(CaptureImport, FramesByNameWhenNotEveryNameHasANumber) {
    fpp::test::TempDir dir;
    for (const char* name : {"b.png", "a10.png", "a2.png"})
        touch(dir / name);
    EXPECT_EQ(listed(dir.path()), (std::vector<std::string>{"a10.png", "a2.png", "b.png"}));
    // Equal numbers: by name.
    fpp::test::TempDir same;
    for (const char* name : {"right_1.png", "left_1.png", "left_0.png"})
        touch(same / name);
    EXPECT_EQ(listed(same.path()),
              (std::vector<std::string>{"left_0.png", "left_1.png", "right_1.png"}));
}

TEST(CaptureImport, FramesOfAFolderThatIsNotThere) {
    fpp::test::TempDir dir;
    try {
        fpp::calib::list_frame_files(dir / "absent");
        FAIL() << "listed a folder that is not there";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), (dir / "absent").string() + ": not a folder of frames");
    }
}

TEST(CaptureImport, SlStudiosModulatedCarrierFramesAreListedSwapped) {
    ImportOptions o;
    o.codec = "modulated";
    o.projector = {1024, 768};
    const fpp::Sequence s = fpp::calib::import_sequence(o, "/frames");
    ASSERT_EQ(fpp::frame_count(s), 12); // 3 shifts x 3 carrier shifts, then the cue's 3
    EXPECT_EQ(fpp::calib::import_frame_order(o, s),
              (std::vector<int>{0, 2, 1, 3, 5, 4, 6, 8, 7, 9, 10, 11}));
    // Every other codec: capture order.
    o.codec = "2x3";
    const fpp::Sequence other = fpp::calib::import_sequence(o, "/frames");
    EXPECT_EQ(fpp::calib::import_frame_order(o, other), (std::vector<int>{0, 1, 2, 3, 4, 5}));
}

TEST(CaptureImport, SequencesOfSomeCodecs) {
    ImportOptions o;
    o.codec = "2x3";
    o.projector = {1024, 768};
    const fpp::Sequence two_by_three = fpp::calib::import_sequence(o, "/frames");
    ASSERT_EQ(two_by_three.size(), 2u);
    const auto& fine = std::get<fpp::PhaseBlock>(two_by_three[0]);
    EXPECT_EQ(fine.period, 64.0); // 1024 / 16 phases
    EXPECT_EQ(fine.steps, 3);
    EXPECT_EQ(std::get<fpp::PhaseBlock>(two_by_three[1]).period, 1024.0); // the one-period cue
    o.direction = "both";
    EXPECT_EQ(fpp::frame_count(fpp::calib::import_sequence(o, "/frames")), 12);

    ImportOptions slmaster;
    slmaster.tool = ImportTool::slmaster;
    slmaster.codec = "interzone";
    slmaster.projector = {320, 96};
    const fpp::Sequence interzone = fpp::calib::import_sequence(slmaster, "/frames");
    ASSERT_EQ(interzone.size(), 2u);
    EXPECT_EQ(fpp::frame_count(interzone[0]), 3); // phase
    const auto& code = std::get<fpp::GrayBlock>(interzone[1]);
    EXPECT_EQ(code.levels, 4);
    EXPECT_EQ(fpp::frame_count(interzone[1]), 2); // log4(16) four-level frames
}

TEST(CaptureImport, OptionsNoToolCanHaveUsedAreRefused) {
    ImportOptions o;
    o.projector = {320, 96};
    o.codec = "4x4";
    EXPECT_EQ(refusal(o).field, "codec");
    EXPECT_EQ(refusal(o).message,
              "unknown SLStudio codec '4x4' (2x3, 3, nstep, 2p1, modulated, graycode, micro)");
    o.codec = "2x3";
    o.projector = {1, 96};
    EXPECT_EQ(refusal(o).field, "projector");
    EXPECT_EQ(refusal(o).message, "projector size 1x96 outside 2..65535");
    ImportOptions slmaster;
    slmaster.tool = ImportTool::slmaster;
    slmaster.codec = "complementary";
    slmaster.projector = {320, 96};
    slmaster.fringes = 6;
    EXPECT_EQ(refusal(slmaster).field, "fringes");
    EXPECT_EQ(refusal(slmaster).message.rfind("SLMaster needs a fringe count (nbrOfPeriods) that "
                                              "is a power of 2 (it shows log2(count) Gray planes); "
                                              "got 6",
                                              0),
              0u)
        << refusal(slmaster).message;
}

} // namespace
