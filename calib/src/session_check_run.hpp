#pragma once
// A session folder checked as `fpp-calib session-check` checks it, for that
// command and for scanner-session's check after each pose.

#include "fpp/calib/session_check.hpp"

#include <filesystem>
#include <functional>
#include <string>

namespace fpp::calib {

// Calibrates the session as `stereo` does (default options, `threads`) and
// checks it; a session with too few usable poses is too weak, not an error.
SessionCheck check_session_folder(const std::filesystem::path& session,
                                  const SessionCheckOptions& options, int threads,
                                  const std::function<void(const std::string&)>& progress);

// 0 enough, 3 not yet, 4 too weak.
int session_check_exit_status(SessionVerdict verdict);

} // namespace fpp::calib
