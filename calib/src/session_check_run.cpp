// A session folder checked as `fpp-calib session-check` checks it.

#include "session_check_run.hpp"

#include "fpp/calib/stereo_session.hpp"

namespace fpp::calib {

SessionCheck check_session_folder(const std::filesystem::path& session,
                                  const SessionCheckOptions& options, int threads,
                                  const std::function<void(const std::string&)>& progress) {
    StereoSessionOptions stereo;
    stereo.stereo.suggest_next_poses = options.suggestions;
    stereo.decode.threads = threads;
    stereo.progress = progress;
    try {
        return check_session(calibrate_session(session, stereo), options);
    } catch (const TooFewPosesError& e) {
        return too_weak_session(e.what(), options);
    }
}

int session_check_exit_status(SessionVerdict verdict) {
    switch (verdict) {
    case SessionVerdict::enough:
        return 0;
    case SessionVerdict::not_yet:
        return 3;
    case SessionVerdict::too_weak:
        return 4;
    }
    return 4;
}

} // namespace fpp::calib
