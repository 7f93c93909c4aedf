// Calibration session folders (fpp/calib/session_folder.hpp): board.yaml and
// the poses' capture sets found by name (a capture set's folder, or an
// fpp-scanner scan holding one in capture/), and each refusal naming the
// file and the field before any frame is read.

#include "fpp/calib/session_folder.hpp"

#include "capture_manifest_fixtures.hpp"
#include "fpp/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <optional>
#include <string>
#include <vector>

using fpp::Axis;
using fpp::BoardDescription;
using fpp::InputError;
using fpp::calib::capture_folders;
using fpp::calib::read_session_folder;
namespace fs = std::filesystem;

namespace {

const std::string kCheckerboard =
    "format: fpp-board/1\nkind: checkerboard\ninner_corners: [13, 9]\nsquare_size: 10.0\n";

void write(const fs::path& file, const std::string& text) {
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text;
}

// board.yaml, pose-02 and pose-01 (capture sets), scan-03 (an fpp-scanner
// scan), and a folder and a file that are neither.
struct Session {
    fpp::test::TempDir dir;
    fs::path path = dir.path();
    Session() {
        write(path / "board.yaml", kCheckerboard);
        write(path / "pose-02" / "capture.yaml", fpp::test::kValid);
        write(path / "pose-01" / "capture.yaml", fpp::test::kValid);
        write(path / "scan-03" / "capture" / "capture.yaml", fpp::test::kValid);
        write(path / "scan-03" / "scan.json", "{}");
        fs::create_directories(path / "notes");
        write(path / "README.txt", "poses of 12 May");
    }
};

struct Refusal {
    fs::path file;
    std::string field, message;
};

// What reading the session refuses: its file, field, and message after them.
Refusal refusal(const fs::path& session,
                std::optional<BoardDescription::Kind> kind = BoardDescription::Kind::checkerboard,
                const std::vector<Axis>& axes = {Axis::x}) {
    try {
        read_session_folder(session, kind, axes, "stereo calibration",
                            "the stereo calibration reads both projector coordinates");
    } catch (const InputError& e) {
        std::string prefix = e.file().string() + ": ";
        if (!e.field().empty())
            prefix += e.field() + ": ";
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
        return {e.file(), e.field(), what.substr(std::min(prefix.size(), what.size()))};
    }
    ADD_FAILURE() << "accepted " << session;
    return {};
}

TEST(SessionFolder, PosesAreFoundByNameScansThroughTheirCaptureFolder) {
    Session s;
    EXPECT_EQ(capture_folders(s.path),
              (std::vector<fs::path>{s.path / "pose-01", s.path / "pose-02",
                                     s.path / "scan-03" / "capture"}));
}

TEST(SessionFolder, ReadsTheBoardAndEveryPosesManifest) {
    Session s;
    const auto session = read_session_folder(s.path, BoardDescription::Kind::checkerboard,
                                             {Axis::x}, "stereo calibration", "");
    EXPECT_EQ(session.folder, s.path);
    EXPECT_EQ(session.board.kind, BoardDescription::Kind::checkerboard);
    ASSERT_EQ(session.poses.size(), 3u);
    ASSERT_EQ(session.manifests.size(), 3u);
    EXPECT_EQ(session.manifests[2].frames.size(), 8u);
    EXPECT_EQ(session.camera_size, (fpp::Size{16, 12}));
    EXPECT_EQ(session.projector_size, (fpp::Size{64, 40}));
    // Any board kind when none is asked for.
    EXPECT_EQ(read_session_folder(s.path, std::nullopt, {}, "a check", "").poses.size(), 3u);
}

TEST(SessionFolder, RefusesAFolderThatIsNotThereOrHasNoBoard) {
    fpp::test::TempDir dir;
    const Refusal absent = refusal(dir / "absent");
    EXPECT_EQ(absent.file, dir / "absent");
    EXPECT_EQ(absent.field, "");
    EXPECT_EQ(absent.message, "not a folder");
    const Refusal no_board = refusal(dir.path());
    EXPECT_EQ(no_board.file, dir / "board.yaml");
    EXPECT_EQ(no_board.message, "missing: a session needs board.yaml (fpp-board/1)");
}

TEST(SessionFolder, RefusesAnotherBoardKindNamingWhatThePurposeNeeds) {
    Session s;
    const Refusal r = refusal(s.path, BoardDescription::Kind::plane);
    EXPECT_EQ(r.file, s.path / "board.yaml");
    EXPECT_EQ(r.field, "kind");
    EXPECT_EQ(r.message, "stereo calibration needs a plane (this board is a checkerboard)");
}

TEST(SessionFolder, RefusesASessionWithoutCaptureSets) {
    fpp::test::TempDir dir;
    write(dir / "board.yaml", kCheckerboard);
    fs::create_directories(dir / "pose-01"); // no capture.yaml in it
    const Refusal r = refusal(dir.path());
    EXPECT_EQ(r.file, dir.path());
    EXPECT_EQ(r.message, "no capture sets (sub-folders holding capture.yaml, or fpp-scanner scans "
                         "holding capture/)");
}

TEST(SessionFolder, RefusesPosesOfAnotherCameraOrProjectorNamingTheFirstPose) {
    Session s;
    const fs::path second = s.path / "pose-02" / "capture.yaml";
    write(second, fpp::test::with("camera:    {width: 16, height: 12}",
                                  "camera:    {width: 32, height: 24}"));
    Refusal r = refusal(s.path);
    EXPECT_EQ(r.file, second);
    EXPECT_EQ(r.field, "camera");
    EXPECT_EQ(r.message, "camera size 32 x 24 differs from pose-01's 16 x 12; all poses must "
                         "come from one camera");
    write(second, fpp::test::with("projector: {width: 64, height: 40}",
                                  "projector: {width: 64, height: 80}"));
    r = refusal(s.path);
    EXPECT_EQ(r.file, second);
    EXPECT_EQ(r.field, "projector");
    EXPECT_EQ(r.message, "projector size 64 x 80 differs from pose-01's 64 x 40");
}

TEST(SessionFolder, RefusesAPoseWithoutAPhaseBlockOnANeededAxis) {
    Session s;
    const Refusal r = refusal(s.path, BoardDescription::Kind::checkerboard, {Axis::x, Axis::y});
    EXPECT_EQ(r.file, s.path / "pose-01" / "capture.yaml");
    EXPECT_EQ(r.field, "sequence");
    EXPECT_EQ(r.message,
              "no phase block along y: the stereo calibration reads both projector coordinates");
}

TEST(SessionFolder, AMalformedManifestIsRefusedByItsReader) {
    Session s;
    write(s.path / "pose-02" / "capture.yaml", fpp::test::with("steps: 3", "steps: two"));
    const Refusal r = refusal(s.path);
    EXPECT_EQ(r.file, s.path / "pose-02" / "capture.yaml");
    EXPECT_EQ(r.field, "sequence[1].steps");
}

} // namespace
