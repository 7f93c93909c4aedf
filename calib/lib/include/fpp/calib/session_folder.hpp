#pragma once
// A calibration session folder: board.yaml (fpp-board/1) and one capture set
// per pose, in name order: any sub-folder holding capture.yaml, or an
// fpp-scanner scan folder holding one in capture/ (a scan store of
// capture-mode scans is a session). Shared by the stereo (checkerboard) and
// hybrid (plane) calibrations.

#include "fpp/capture_set.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fpp::calib {

struct SessionFolder {
    std::filesystem::path folder;
    BoardDescription board;
    std::vector<std::filesystem::path> poses; // capture set folders, by name
    std::vector<CaptureManifest> manifests;   // one per pose
    Size camera_size;
    Size projector_size;
};

// Reads board.yaml and every pose's manifest and checks that they agree:
// `kind` is the board that `purpose` (e.g. "stereo calibration") needs (any
// when empty),
// every pose has the same camera and projector sizes and a phase block along
// each axis in `axes` (`axes_reason` says why, for the message). Throws InputError naming the file
// and the field: no folder, no board.yaml, another board kind, no capture sets, differing sizes, a
// missing phase axis.
SessionFolder read_session_folder(const std::filesystem::path& session,
                                  std::optional<BoardDescription::Kind> kind,
                                  const std::vector<Axis>& axes, const std::string& purpose,
                                  const std::string& axes_reason);

// The capture set folders of `session` (sub/ or sub/capture/), by name.
std::vector<std::filesystem::path> capture_folders(const std::filesystem::path& session);

} // namespace fpp::calib
