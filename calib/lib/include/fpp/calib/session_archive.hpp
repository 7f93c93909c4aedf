#pragma once
// A calibration session's tar as fpp-scanner serves it (GET
// /api/v1/sessions/NAME/session.tar: NAME/board.yaml, NAME/{id}/scan.json,
// NAME/{id}/capture/...) unpacked into a session folder for `fpp-calib
// calibrate`: board.yaml and the pose folders, without the NAME/ level.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fpp::calib {

struct ExtractedSession {
    std::vector<std::string> poses; // the folders beside board.yaml, by name
    std::size_t files = 0;
    std::uint64_t bytes = 0;
};

// Extracts `tar` (read with libarchive) into the new folder `target`, which
// must not exist and appears whole or not at all (write_folder_atomically;
// one syncfs before the rename). Only folders and regular files under
// `session`/ are taken: an entry with an absolute path or a `..`, outside
// `session`/, of another kind (link, device) or twice in the archive is
// refused, naming it, as is an archive without board.yaml. Throws
// InputError(tar, entry, why), IoError.
ExtractedSession extract_session_tar(const std::filesystem::path& tar, const std::string& session,
                                     const std::filesystem::path& target);

} // namespace fpp::calib
