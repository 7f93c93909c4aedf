#pragma once
// Report folders (summary.md and PNG figures) written as a whole: a reader
// never sees half a report, and an earlier report in the same place is
// replaced only once the new one is complete.

#include <opencv2/core.hpp>

#include <filesystem>
#include <functional>

namespace fpp::calib {

// Whether `folder` may receive a report: absent, an empty folder, or an
// earlier report (holding summary.md), which is replaced.
bool report_folder_writable(const std::filesystem::path& folder);

// Calls `write` with a fresh temporary folder and, once it is complete, puts
// it in place of `folder` (an earlier report there is replaced then, and
// left untouched if writing fails). `write` must fsync what it
// writes (write_file_synced, save_png). Throws InputError if `folder` exists
// and is not a report, IoError on OS failures.
void write_report_folder(const std::filesystem::path& folder,
                         const std::function<void(const std::filesystem::path& temp)>& write);

// Writes an 8-bit image as PNG and fsyncs it. Throws IoError.
void save_png(const std::filesystem::path& path, const cv::Mat& image);

} // namespace fpp::calib
