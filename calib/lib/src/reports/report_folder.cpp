// Report folders written as a whole.

#include "fpp/calib/report_folder.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"

#include <opencv2/imgcodecs.hpp>

#include <system_error>

namespace fpp::calib {

namespace fs = std::filesystem;

bool report_folder_writable(const fs::path& folder) {
    std::error_code ec;
    if (!fs::exists(folder, ec))
        return true;
    if (!fs::is_directory(folder, ec))
        return false;
    return fs::is_empty(folder, ec) || fs::exists(folder / "summary.md", ec);
}

void write_report_folder(const fs::path& folder,
                         const std::function<void(const fs::path& temp)>& write) {
    if (!report_folder_writable(folder))
        throw InputError(folder, "", "exists and is not a report; choose another report folder");
    const fs::path target = folder.filename().empty() ? folder.parent_path() : folder;
    // The new report is written completely beside the target first; only
    // then does the earlier one step aside, so a failure leaves it as it was.
    fs::path staging = target;
    staging += ".new";
    fs::path old = target;
    old += ".old";
    std::error_code ec;
    fs::remove_all(staging, ec); // a leftover of an interrupted run
    write_folder_atomically(staging, write);
    if (fs::exists(target, ec)) {
        fs::remove_all(old, ec);
        fs::rename(target, old);
        fs::rename(staging, target);
        fs::remove_all(old, ec);
    } else {
        fs::rename(staging, target);
    }
    fsync_path(target.has_parent_path() ? target.parent_path() : fs::path("."));
}

void save_png(const fs::path& path, const cv::Mat& image) {
    if (!cv::imwrite(path.string(), image))
        throw IoError(path, "cannot write the PNG");
    fsync_path(path);
}

} // namespace fpp::calib
