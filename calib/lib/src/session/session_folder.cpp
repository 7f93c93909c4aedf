// Session folder reading and validation, before any frame is decoded.

#include "fpp/calib/session_folder.hpp"

#include "fpp/error.hpp"

#include <algorithm>
#include <system_error>
#include <variant>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

bool has_phase(const Sequence& sequence, Axis axis) {
    for (const PatternBlock& b : sequence)
        if (const auto* p = std::get_if<PhaseBlock>(&b); p && p->axis == axis)
            return true;
    return false;
}

std::string size_text(Size s) {
    return std::to_string(s.width) + " x " + std::to_string(s.height);
}

const char* kind_text(BoardDescription::Kind kind) {
    return kind == BoardDescription::Kind::checkerboard ? "checkerboard" : "plane";
}

} // namespace

std::vector<fs::path> capture_folders(const fs::path& session) {
    std::vector<fs::path> out;
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(session, ec)) {
        if (!e.is_directory())
            continue;
        if (fs::exists(e.path() / "capture.yaml"))
            out.push_back(e.path());
        else if (fs::exists(e.path() / "capture" / "capture.yaml")) // an fpp-scanner scan
            out.push_back(e.path() / "capture");
    }
    if (ec)
        throw InputError(session, "", "cannot list the folder: " + ec.message());
    std::sort(out.begin(), out.end());
    return out;
}

SessionFolder read_session_folder(const fs::path& session,
                                  std::optional<BoardDescription::Kind> kind,
                                  const std::vector<Axis>& axes, const std::string& purpose,
                                  const std::string& axes_reason) {
    SessionFolder s;
    s.folder = session;
    if (!fs::is_directory(session))
        throw InputError(session, "", "not a folder");
    const fs::path board_file = session / "board.yaml";
    if (!fs::exists(board_file))
        throw InputError(board_file, "", "missing: a session needs board.yaml (fpp-board/1)");
    s.board = read_board(board_file);
    if (kind && s.board.kind != *kind)
        throw InputError(board_file, "kind",
                         purpose + " needs a " + kind_text(*kind) + " (this board is a " +
                             kind_text(s.board.kind) + ")");
    s.poses = capture_folders(session);
    if (s.poses.empty())
        throw InputError(session, "",
                         "no capture sets (sub-folders holding capture.yaml, or fpp-scanner scans "
                         "holding capture/)");
    for (const fs::path& f : s.poses) {
        const fs::path yaml = f / "capture.yaml";
        s.manifests.push_back(read_manifest(yaml));
        const CaptureManifest& m = s.manifests.back();
        if (s.manifests.size() == 1) {
            s.camera_size = m.camera;
            s.projector_size = m.projector;
        } else if (!(m.camera == s.camera_size)) {
            throw InputError(yaml, "camera",
                             "camera size " + size_text(m.camera) + " differs from " +
                                 s.poses.front().filename().string() + "'s " +
                                 size_text(s.camera_size) +
                                 "; all poses must come from one camera");
        } else if (!(m.projector == s.projector_size)) {
            throw InputError(yaml, "projector",
                             "projector size " + size_text(m.projector) + " differs from " +
                                 s.poses.front().filename().string() + "'s " +
                                 size_text(s.projector_size));
        }
        for (Axis axis : axes)
            if (!has_phase(m.sequence, axis))
                throw InputError(yaml, "sequence",
                                 std::string("no phase block along ") + to_string(axis) + ": " +
                                     axes_reason);
    }
    return s;
}

} // namespace fpp::calib
