// Report folders written as a whole (fpp/calib/report_folder.hpp): where a
// report may go, the new report in place only once complete (an earlier one
// replaced then, kept when writing fails), nothing left beside it, a folder
// that is not a report refused, and the PNG writer.

#include "fpp/calib/report_folder.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using fpp::calib::report_folder_writable;
using fpp::calib::save_png;
using fpp::calib::write_report_folder;
namespace fs = std::filesystem;

namespace {

std::string text_of(const fs::path& file) {
    std::ifstream in(file);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::vector<fs::path> names_in(const fs::path& folder) {
    std::vector<fs::path> names;
    for (const fs::path& p : fpp::test::entries_under(folder))
        names.push_back(fs::relative(p, folder));
    std::sort(names.begin(), names.end());
    return names;
}

void write_summary(const fs::path& temp, const std::string& text) {
    fpp::write_file_synced(temp / "summary.md", text);
}

TEST(ReportFolder, WhereAReportMayGo) {
    fpp::test::TempDir dir;
    EXPECT_TRUE(report_folder_writable(dir / "absent"));
    fs::create_directories(dir / "empty");
    EXPECT_TRUE(report_folder_writable(dir / "empty"));
    fs::create_directories(dir / "earlier");
    std::ofstream(dir / "earlier" / "summary.md") << "# earlier\n";
    EXPECT_TRUE(report_folder_writable(dir / "earlier"));
    fs::create_directories(dir / "photos");
    std::ofstream(dir / "photos" / "board.jpg") << "jpeg";
    EXPECT_FALSE(report_folder_writable(dir / "photos"));
    std::ofstream(dir / "file") << "a file";
    EXPECT_FALSE(report_folder_writable(dir / "file"));
}

TEST(ReportFolder, ANewReportIsPutInPlaceWhole) {
    fpp::test::TempDir dir;
    const fs::path report = dir / "report";
    write_report_folder(report, [&](const fs::path& temp) {
        EXPECT_NE(temp, report);
        EXPECT_FALSE(fs::exists(report)); // not there until complete
        write_summary(temp, "# first\n");
        fs::create_directories(temp / "figures");
        fpp::write_file_synced(temp / "figures" / "a.txt", "a");
    });
    EXPECT_EQ(text_of(report / "summary.md"), "# first\n");
    EXPECT_EQ(names_in(dir.path()),
              (std::vector<fs::path>{"report", "report/figures", "report/figures/a.txt",
                                     "report/summary.md"}));
}

TEST(ReportFolder, AnEarlierReportIsReplacedOnlyOnceTheNewOneIsComplete) {
    fpp::test::TempDir dir;
    const fs::path report = dir / "report";
    write_report_folder(report, [](const fs::path& temp) {
        write_summary(temp, "# first\n");
        fpp::write_file_synced(temp / "old.png", "png");
    });
    write_report_folder(report, [&](const fs::path& temp) {
        EXPECT_EQ(text_of(report / "summary.md"), "# first\n"); // still the earlier one
        write_summary(temp, "# second\n");
    });
    EXPECT_EQ(text_of(report / "summary.md"), "# second\n");
    EXPECT_EQ(names_in(dir.path()), (std::vector<fs::path>{"report", "report/summary.md"}));
}

TEST(ReportFolder, AFailedWriteLeavesTheEarlierReportAndNothingElse) {
    fpp::test::TempDir dir;
    const fs::path report = dir / "report";
    write_report_folder(report, [](const fs::path& temp) { write_summary(temp, "# first\n"); });
    EXPECT_THROW(write_report_folder(report,
                                     [](const fs::path& temp) {
                                         write_summary(temp, "# half\n");
                                         throw std::runtime_error("figure failed");
                                     }),
                 std::runtime_error);
    EXPECT_EQ(text_of(report / "summary.md"), "# first\n");
    EXPECT_EQ(names_in(dir.path()), (std::vector<fs::path>{"report", "report/summary.md"}));
}

TEST(ReportFolder, AFolderThatIsNotAReportIsRefusedAndKept) {
    fpp::test::TempDir dir;
    const fs::path photos = dir / "photos";
    fs::create_directories(photos);
    std::ofstream(photos / "board.jpg") << "jpeg";
    bool written = false;
    try {
        write_report_folder(photos, [&](const fs::path&) { written = true; });
        FAIL() << "wrote a report over " << photos;
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), photos);
        EXPECT_EQ(e.field(), "");
        EXPECT_EQ(std::string(e.what()),
                  photos.string() + ": exists and is not a report; choose another report folder");
    }
    EXPECT_FALSE(written);
    EXPECT_EQ(names_in(dir.path()), (std::vector<fs::path>{"photos", "photos/board.jpg"}));
}

TEST(ReportFolder, AFolderNamedWithATrailingSlash) {
    fpp::test::TempDir dir;
    write_report_folder(dir.path() / "report" / "",
                        [](const fs::path& temp) { write_summary(temp, "# slash\n"); });
    EXPECT_EQ(text_of(dir / "report" / "summary.md"), "# slash\n");
    EXPECT_EQ(names_in(dir.path()), (std::vector<fs::path>{"report", "report/summary.md"}));
}

TEST(ReportFolder, SavePngWritesAnImageThatReadsBack) {
    fpp::test::TempDir dir;
    cv::Mat image(3, 4, CV_8UC3, cv::Scalar(10, 20, 30));
    image.at<cv::Vec3b>(2, 3) = cv::Vec3b(200, 100, 50);
    save_png(dir / "figure.png", image);
    const cv::Mat back = cv::imread((dir / "figure.png").string(), cv::IMREAD_COLOR);
    ASSERT_EQ(back.rows, 3);
    ASSERT_EQ(back.cols, 4);
    EXPECT_EQ(back.at<cv::Vec3b>(0, 0), cv::Vec3b(10, 20, 30));
    EXPECT_EQ(back.at<cv::Vec3b>(2, 3), cv::Vec3b(200, 100, 50));
    try {
        save_png(dir / "absent" / "figure.png", image);
        FAIL() << "wrote into a folder that is not there";
    } catch (const fpp::IoError& e) {
        EXPECT_EQ(std::string(e.what()),
                  (dir / "absent" / "figure.png").string() + ": cannot write the PNG");
    }
}

} // namespace
