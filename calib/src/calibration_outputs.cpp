#include "calibration_outputs.hpp"

#include "fpp/calib/calibration_report.hpp"
#include "fpp/calib/hybrid_report.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"

#include <iomanip>
#include <iostream>

namespace fpp::calib {

void check_output_file(const std::filesystem::path& out, const std::string& option) {
    if (std::filesystem::is_directory(out))
        throw InputError(out, "", "is a folder; " + option);
}

void check_report_folder(const std::string& report, const std::string& what) {
    if (!report.empty() && !report_folder_writable(report))
        throw InputError(report, "",
                         "exists and is not a " + what + " report; choose another folder");
}

StereoCalibration session_calibration(const SessionResult& result) {
    const StereoResult& s = result.stereo;
    StereoCalibration calibration = s.calibration;
    // Every pose of the session in order; skipped ones with their reason.
    calibration.poses.clear();
    std::size_t next = 0;
    for (const SessionPose& p : result.poses) {
        if (p.usable) {
            calibration.poses.push_back(s.calibration.poses.at(next++));
            continue;
        }
        PoseResidual r;
        r.name = p.name;
        r.used = false;
        r.note = "skipped: " + p.skip_reason;
        calibration.poses.push_back(r);
    }
    return calibration;
}

void write_stereo_outputs(const SessionResult& result, const std::filesystem::path& out,
                          const std::string& report, const HeldOutCheck* held_out) {
    const StereoResult& s = result.stereo;
    if (!report.empty()) {
        std::cerr << "writing the report to " << report << "\n";
        write_calibration_report(report, result, held_out);
    }
    const StereoCalibration calibration = session_calibration(result);
    save_calibration(out, calibration);
    std::cerr << "time per stage (s, summed over the threads running it): "
              << result.time_split.summary() << "\n";

    std::cout << std::fixed << std::setprecision(4) << "calibrated from "
              << result.calibrated.size() << " of " << result.poses.size() << " poses: camera RMS "
              << s.calibration.camera_rms << " px, projector RMS " << s.calibration.projector_rms
              << " px (skew " << (s.skew_estimated ? "estimated" : "fixed at 0") << ", corners by "
              << to_string(result.method) << ")\n"
              << std::setprecision(2) << "camera fu " << s.calibration.camera.fu << " fv "
              << s.calibration.camera.fv << ", projector fu " << s.calibration.projector.fu
              << " fv " << s.calibration.projector.fv << "\n"
              << trueness_summary(s.calibration.trueness);
    if (!s.next_poses.empty())
        std::cout << "to shrink it most, the next pose: " << s.next_poses.front().words() << "\n";
    std::cout << "wrote " << out.string() << " in " << result.seconds_total << " s\n";
}

void write_hybrid_outputs(const HybridResult& result, const std::filesystem::path& out,
                          const std::string& report) {
    if (!report.empty()) {
        std::cerr << "writing the report to " << report << "\n";
        write_hybrid_report(report, result);
    }
    write_table(out, result.table);
    std::cerr << "time per stage (s, summed over the threads running it): "
              << result.time_split.summary() << "\n";
    std::cout << result.summary() << trueness_summary(result.trueness) << "wrote " << out.string()
              << "\n";
}

} // namespace fpp::calib
